"""export_mjcf: what it writes and its one-line errors (MuJoCo itself loads it in test/consumers)."""
import os
import xml.etree.ElementTree as ElementTree

import pytest

from ur3_ft_gripper_testing.model import EXPORT_MJCF, run_export


def export_mjcf(*args):
    return run_export(*args, command=EXPORT_MJCF)


def test_mjcf_has_the_mimic_equalities_stl_meshes_and_the_linkage_exclusions(tmp_path):
    out = tmp_path / 'ur3.xml'
    run = export_mjcf('-o', str(out))
    assert run.returncode == 0, run.stderr
    root = ElementTree.parse(str(out)).getroot()
    mimics = root.findall('equality/joint')
    assert sorted(m.get('joint2') for m in mimics) == ['finger_joint'] * 5
    files = [m.get('file') for m in root.iter('mesh')]
    assert files and all(f.endswith('.stl') and os.path.isfile(f) for f in files)
    assert all(os.path.dirname(f) == str(tmp_path / 'ur3_meshes') for f in files)
    excluded = {tuple(sorted((e.get('body1'), e.get('body2')))) for e in root.iter('exclude')}
    assert ('left_inner_finger', 'left_inner_knuckle') in excluded
    assert root.find("actuator/position[@joint='finger_joint']") is not None


def test_world_link_is_mujocos_world_body(tmp_path):
    out = tmp_path / 'world.xml'
    assert export_mjcf('--world', '-o', str(out)).returncode == 0
    root = ElementTree.parse(str(out)).getroot()
    assert [b.get('name') for b in root.find('worldbody')] == ['base_link']
    assert 'world' not in [b.get('name') for b in root.iter('body')]


def test_prefix_reaches_bodies_joints_and_exclusions(tmp_path):
    out = tmp_path / 'left.xml'
    assert export_mjcf('--prefix', 'left_', '-o', str(out)).returncode == 0
    root = ElementTree.parse(str(out)).getroot()
    names = [b.get('name') for b in root.iter('body')] + [j.get('name') for j in root.iter('joint')
                                                          if j.get('name')]
    assert names and all(n.startswith('left_') for n in names)
    assert all(e.get('body1').startswith('left_') for e in root.iter('exclude'))


@pytest.mark.parametrize('options,words', [
    (['--no-such-option', '-o', '{tmp}/m.xml'], ['unrecognized arguments: --no-such-option']),
    ([], ['-o/--output']),
    (['-o', '/proc/no/such/folder/m.xml'], ['cannot write /proc/no/such/folder/m.xml', 'give -o']),
    (['--ur-type', 'ur7', '-o', '{tmp}/m.xml'], ['config/ur7/', 'has the models ur3']),
])
def test_bad_input_is_one_line(tmp_path, options, words):
    run = export_mjcf(*[o.format(tmp=tmp_path) for o in options])
    assert run.returncode == 1 and run.stdout == ''
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('export_mjcf: error: '), run.stderr
    for word in words:
        assert word in lines[0], (word, lines[0])
    assert not os.path.exists(str(tmp_path / 'm.xml'))


def test_physics_drives_every_arm_joint_within_the_urdfs_effort_limits(tmp_path, default_model):
    out = tmp_path / 'ur3.xml'
    assert export_mjcf('-o', str(out)).returncode == 0
    root = ElementTree.parse(str(out)).getroot()
    assert root.find('compiler').get('fusestatic') == 'false'  # the FT 300's frame stays a body
    joints = {j.get('name'): j for j in root.iter('joint')}
    arm = [name for name in default_model.joints if default_model.joints[name].type != 'fixed' and
           default_model.joints[name].mimic is None and name != 'finger_joint']
    assert len(arm) == 6
    for name in arm:
        effort = default_model.joints[name].limit.effort
        assert [float(v) for v in joints[name].get('actuatorfrcrange').split()] == [-effort, effort], name
        assert joints[name].get('actuatorgravcomp') == 'true'
        assert root.find("actuator/position[@joint='%s']" % name).get('name') == name
        assert root.find("actuator/velocity[@joint='%s']" % name).get('name') == name + '_velocity'
    assert all(body.get('gravcomp') == '1' for body in root.iter('body'))


def test_the_ft300_frame_carries_the_force_and_torque_sensors(tmp_path):
    out = tmp_path / 'left.xml'
    assert export_mjcf('--prefix', 'left_', '-o', str(out)).returncode == 0
    root = ElementTree.parse(str(out)).getroot()
    frame = root.find(".//body[@name='left_robotiq_ft_frame_id']")
    assert frame.find("site[@name='left_robotiq_ft_frame_id']") is not None
    assert [s.get('site') for s in root.findall("sensor/force")] == ['left_tool0', 'left_robotiq_ft_frame_id']
    assert [s.get('site') for s in root.findall("sensor/torque")] == ['left_tool0', 'left_robotiq_ft_frame_id']
    assert root.find(".//body[@name='left_tool0']/site[@name='left_tool0']") is not None
    pads = [g for g in root.iter('geom') if 'inner_finger_pad' in g.get('name')]
    assert len(pads) == 2 and all(g.get('priority') == '1' and g.get('condim') for g in pads)


def test_without_the_ft300_only_the_flange_has_a_sensor(tmp_path):
    out = tmp_path / 'noft.xml'
    assert export_mjcf('--no-ft-sensor', '-o', str(out)).returncode == 0
    root = ElementTree.parse(str(out)).getroot()
    assert [s.get('site') for s in root.find('sensor')] == ['tool0', 'tool0']
    assert [s.get('name') for s in root.iter('site')] == ['tool0']
