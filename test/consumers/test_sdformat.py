"""The URDF through libsdformat, the converter Gazebo runs at spawn (a small C++ program of ours)."""
import os
import subprocess
import xml.etree.ElementTree as ElementTree

import pytest

from conftest import FOLDER, FRAMES_TOLERANCE, GRIPPER_LINKS, expected_total_mass, exported_urdf

SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'sdformat_model.cc')


@pytest.fixture(scope='module')
def sdformat_model():
    """The program, built against the installed libsdformat (sdformat12 on Debian 12, sdformat9 on Noetic)."""
    modules = [m for m in ('sdformat12', 'sdformat9')
               if subprocess.run(['pkg-config', '--exists', m]).returncode == 0]
    assert modules, 'libsdformat is not installed: apt install libsdformat-dev (Debian 12) or libsdformat9-dev'
    flags = subprocess.run(['pkg-config', '--cflags', '--libs', modules[0]], stdout=subprocess.PIPE,
                           universal_newlines=True, check=True).stdout.split()
    program = os.path.join(FOLDER, 'sdformat_model')
    subprocess.run(['c++', '-std=c++17', '-o', program, SOURCE] + flags, check=True, timeout=600)
    return program


def converted(program, urdf_path, preserved=()):
    """{link: mass}, {joint: (parent, child)} of the SDF that libsdformat makes of the URDF."""
    root = ElementTree.parse(urdf_path).getroot()
    for joint in preserved:  # as a user who attaches an FT-sensor plugin writes it
        gazebo = ElementTree.SubElement(root, 'gazebo', reference=joint)
        ElementTree.SubElement(gazebo, 'preserveFixedJoint').text = 'true'
    path = '%s-%s.urdf' % (os.path.splitext(urdf_path)[0], '-'.join(preserved) or 'plain')
    ElementTree.ElementTree(root).write(path)
    done = subprocess.run([program, path], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, timeout=120)
    assert done.returncode == 0, done.stderr
    links, joints = {}, {}
    for line in done.stdout.splitlines():
        words = line.split()
        if words[0] == 'link':
            links[words[1]] = float(words[2])
        elif words[0] == 'joint':
            joints[words[1]] = (words[3], words[4])
    return links, joints


def urdf_masses(urdf_path):
    return {link.get('name'): float(link.find('inertial/mass').get('value'))
            for link in ElementTree.parse(urdf_path).getroot().findall('link')
            if link.find('inertial') is not None}


@pytest.mark.parametrize('preserved',
                         [(), ('ft300_fix',), ('ft_gripper_joint',), ('ft300_fix', 'ft_gripper_joint')],
                         ids=['lumped', 'ft300_fix', 'ft_gripper_joint', 'both'])
def test_sensor_and_gripper_chain_survive_the_conversion(sdformat_model, preserved):
    urdf = exported_urdf()
    links, joints = converted(sdformat_model, urdf, preserved)
    # Kept as links of their own: the child of every moving or preserved joint;
    # the rest is lumped into them (their mass counted below).
    tree = ElementTree.parse(urdf).getroot().findall('joint')
    kept = [j.find('child').get('link') for j in tree
            if j.get('type') != 'fixed' or j.get('name') in preserved]
    assert set(GRIPPER_LINKS) & set(kept)
    for link in kept:
        assert link in links, (link, sorted(links))
    for joint in preserved:
        assert joint in joints, (joint, sorted(joints))
    assert joints.get('ft300_fix', ('', 'ft300_mounting_plate'))[1] == 'ft300_mounting_plate'
    assert joints.get('ft_gripper_joint', ('', 'robotiq_arg2f_base_link'))[1] == 'robotiq_arg2f_base_link'
    assert sum(links.values()) == pytest.approx(sum(urdf_masses(urdf).values()), abs=1e-6)
    assert sum(links.values()) == pytest.approx(expected_total_mass([]), abs=FRAMES_TOLERANCE)


@pytest.mark.parametrize('options', [['--no-ft-sensor'], ['--no-gripper']], ids=['gripper', 'ft_sensor'])
def test_each_part_alone_keeps_its_mass(sdformat_model, options):
    links, _ = converted(sdformat_model, exported_urdf(*options))
    assert sum(links.values()) == pytest.approx(expected_total_mass(options), abs=FRAMES_TOLERANCE)
