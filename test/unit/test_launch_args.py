"""Every argument of the load launch reaches the model from the view launches too; every package
the launch files name is declared."""
import glob
import os
import re
import subprocess
import xml.etree.ElementTree as ElementTree

import pytest
import yaml
from catkin_pkg.package import parse_package

from ur3_ft_gripper_testing.model import PACKAGE_DIR

PACKAGE = 'ur3_ft_gripper_description'
# Each view launch with the arguments it requires.
VIEW_LAUNCHES = {'view_ur3_ft_gripper.launch': [], 'view_ur_ft_gripper.launch': ['ur_type:=ur3']}


def launch_args(launch_file):
    """The names roslaunch lists for `roslaunch --ros-args` (required and optional)."""
    run = subprocess.run(['roslaunch', '--ros-args', PACKAGE, launch_file], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True, timeout=60)
    assert run.returncode == 0, run.stderr
    return set(re.findall(r'^  (\w+)(?: \(default|:)', run.stdout, re.MULTILINE))


def dumped_description(launch_file, *args):
    run = subprocess.run(['roslaunch', '--dump-params', PACKAGE, launch_file] + list(args),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                         timeout=120)
    assert run.returncode == 0 and run.stdout, run.stderr
    return run.stdout


@pytest.mark.parametrize('view', sorted(VIEW_LAUNCHES))
def test_view_launch_takes_every_load_argument(view):
    missing = launch_args('load_ur_ft_gripper.launch') - launch_args(view) - {'ur_type'}
    assert not missing, 'load arguments the view launch cannot pass on: %s' % sorted(missing)


@pytest.mark.parametrize('view', sorted(VIEW_LAUNCHES))
def test_view_launch_passes_transmission_and_safety_arguments_to_the_model(view):
    text = dumped_description(view, *VIEW_LAUNCHES[view] + [
        'safety_limits:=true', 'safety_pos_margin:=0.25', 'safety_k_position:=33',
        'transmission_hw_interface:=hardware_interface/EffortJointInterface'])
    # Every arm joint's transmission takes the argument; the gripper's keeps its own.
    urdf = yaml.safe_load(text)['/robot_description']
    for joint in ('shoulder_pan', 'shoulder_lift', 'elbow', 'wrist_1', 'wrist_2', 'wrist_3'):
        interfaces = re.findall(r'<joint name="%s_joint">\s*<hardwareInterface>([^<]*)<' % joint, urdf)
        assert interfaces == ['hardware_interface/EffortJointInterface'], (joint, interfaces)
    assert 'k_position=\\"33\\"' in text
    assert 'soft_lower_limit=\\"-6.03318530' in text  # -2 pi + the margin 0.25


def test_every_package_a_launch_file_names_is_a_run_dependency():
    # package.xml keeps only what runs the model, the launch files and the
    # nodes; a package named by a launch file must stay among them.
    declared = {d.name for d in parse_package(PACKAGE_DIR).exec_depends}
    named = {}
    for path in glob.glob(os.path.join(PACKAGE_DIR, 'launch', '**', '*.launch'), recursive=True):
        for element in ElementTree.parse(path).iter():
            packages = [element.get('pkg')] + re.findall(r'\$\(find (\w+)\)', ' '.join(element.attrib.values()))
            for package in filter(None, packages):
                named.setdefault(package, os.path.basename(path))
    assert 'ur_robot_driver' in named and 'rviz' in named  # the parse found the bring-up and the view
    undeclared = {p: f for p, f in named.items() if p != PACKAGE and p not in declared}
    assert not undeclared, 'named in launch files, not exec_depend in package.xml: %s' % undeclared
