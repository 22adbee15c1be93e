"""The expanded UR3 + FT 300 + 2F-140 model, checked with domain assertions."""
import os
import subprocess
import textwrap

import numpy as np
import pytest
import yaml

from ur3_ft_gripper_description.model import description
from ur3_ft_gripper_testing.model import PACKAGE_DIR, UR_CONFIG, ExpandedModel, robotiq_variant

SENSOR_CHAIN = ['tool0', 'ft300_mounting_plate', 'ft300_sensor', 'robotiq_ft_frame_id',
                'robotiq_arg2f_base_link']
MIMIC_JOINTS = {  # multiplier of finger_joint, the same in both robotiq layouts
    'left_inner_knuckle_joint': -1.0, 'left_inner_finger_joint': 1.0,
    'right_inner_knuckle_joint': -1.0, 'right_inner_finger_joint': 1.0,
}
RIGHT_OUTER_KNUCKLE = {'noetic': 'right_finger_joint', 'kinetic': 'right_outer_knuckle_joint'}


def test_check_urdf_accepts_the_model(default_model, tmp_path):
    urdf = tmp_path / 'model.urdf'
    urdf.write_text(default_model.text)
    run = subprocess.run(['check_urdf', str(urdf)], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, universal_newlines=True)
    assert run.returncode == 0, run.stdout
    assert 'root Link: base_link' in run.stdout


def test_one_root_base_link_and_no_world(default_model):
    assert default_model.root() == 'base_link'
    default_model.assert_lacks_link('world')


def test_link_and_joint_names_are_unique(default_model):
    assert len(default_model.links) == len(set(default_model.links))
    assert default_model.links.count('base_link') == 1


def test_forked_gripper_root_is_removed(default_model):
    # The jr-robotics macro emits base_link -> robotiq_arg2f_base_link; the
    # gripper must hang from the sensor instead, whatever layout is installed.
    assert 'base_link-robotiq_arg2f_base_link' not in default_model.joints
    assert default_model.parent_joint['robotiq_arg2f_base_link'].name == 'ft_gripper_joint'


def test_sensor_and_gripper_chain_hangs_from_tool0(default_model):
    for parent, child in zip(SENSOR_CHAIN, SENSOR_CHAIN[1:]):
        default_model.assert_joint_between(parent, child, 'fixed')
    assert default_model.parent_joint['robotiq_arg2f_base_link'].name == 'ft_gripper_joint'
    assert default_model.path_to_root('tool0')[-1] == 'base_link'


@pytest.mark.parametrize('pad', ['left_inner_finger_pad', 'right_inner_finger_pad'])
def test_finger_pads_hang_from_the_gripper_base(default_model, pad):
    assert 'robotiq_arg2f_base_link' in default_model.path_to_root(pad)


def test_finger_joint_is_the_actuated_joint(default_model):
    joint = default_model.joints['finger_joint']
    assert joint.type == 'revolute'
    assert default_model.limits('finger_joint') == (0.0, 0.7)
    assert default_model.mimic_of('finger_joint') is None


def test_five_mimic_joints_follow_finger_joint(default_model):
    expected = dict(MIMIC_JOINTS, **{RIGHT_OUTER_KNUCKLE[robotiq_variant()]: -1.0})
    mimics = {name: default_model.mimic_of(name) for name in default_model.joints
              if default_model.mimic_of(name)}
    assert sorted(mimics) == sorted(expected)
    for name, multiplier in expected.items():
        assert mimics[name] == ('finger_joint', multiplier, 0.0), name


def test_meshes_are_upstream_package_uris_that_resolve(default_model):
    meshes = default_model.meshes()
    assert len(meshes) > 20
    for mesh in meshes:
        default_model.assert_mesh_resolves(mesh)


def test_tool0_to_gripper_is_the_upstream_ft300_offset(default_model):
    """tool0 -> robotiq_arg2f_base_link = upstream FT 300 macro, then the gripper mount."""
    ft300_alone = os.path.join(PACKAGE_DIR, 'test', 'data', 'ft300_alone.xacro')
    upstream = ExpandedModel(description.to_xml(description.run_xacro(ft300_alone)))
    expected = upstream.transform('tool0', 'robotiq_ft_frame_id')
    actual = default_model.transform('tool0', 'robotiq_arg2f_base_link')
    np.testing.assert_allclose(actual, expected, atol=1e-9)
    # 41.5 mm out along the flange axis, z still pointing away from the arm
    np.testing.assert_allclose(actual[:3, 3], [0, 0, 0.0415], atol=1e-9)
    np.testing.assert_allclose(actual[:3, 2], [0, 0, 1], atol=1e-9)


def test_calibration_file_moves_the_arm_joints(expand_model, tmp_path):
    with open(os.path.join(UR_CONFIG, 'default_kinematics.yaml')) as f:
        calibration = yaml.safe_load(f)
    calibration['kinematics']['shoulder']['z'] = 0.2
    calibration['kinematics']['forearm']['x'] = -0.25
    path = tmp_path / 'my_robot_calibration.yaml'
    path.write_text(yaml.safe_dump(calibration))
    model = expand_model(kinematics_params=str(path))
    assert model.origin_xyz('shoulder_pan_joint')[2] == pytest.approx(0.2)
    assert model.origin_xyz('elbow_joint')[0] == pytest.approx(-0.25)
    default = expand_model()
    assert default.origin_xyz('shoulder_pan_joint')[2] == pytest.approx(0.1519)


@pytest.mark.parametrize('arg,source,key,value,read', [
    ('joint_limit_params', 'joint_limits.yaml', ('joint_limits', 'elbow_joint', 'max_position'), 1.5,
     lambda m: m.limits('elbow_joint')[1]),
    ('physical_params', 'physical_parameters.yaml', ('inertia_parameters', 'shoulder_mass'), 2.5,
     lambda m: m.mass('shoulder_link')),
    ('visual_params', 'visual_parameters.yaml', ('mesh_files', 'base', 'visual', 'mesh'),
     'package://ur_description/meshes/ur5/visual/base.dae',
     lambda m: m.meshes('base_link_inertia')[0].filename),
])
def test_other_parameter_files_are_passed_through(expand_model, tmp_path, arg, source, key, value, read):
    with open(os.path.join(UR_CONFIG, source)) as f:
        data = yaml.safe_load(f)
    node = data
    for k in key[:-1]:
        node = node[k]
    assert node[key[-1]] != value
    node[key[-1]] = value
    path = tmp_path / source
    path.write_text(yaml.safe_dump(data))
    assert read(expand_model(**{arg: str(path)})) == value


def test_prefix_reaches_every_link_and_joint(expand_model):
    model = expand_model(prefix='r1_')
    assert model.root() == 'r1_base_link'
    assert all(name.startswith('r1_') for name in model.links), model.links
    assert all(name.startswith('r1_') for name in model.joints), list(model.joints)
    assert all(model.mimic_of(name)[0] == 'r1_finger_joint' for name in model.joints if model.mimic_of(name))
    assert model.parent_joint['r1_robotiq_arg2f_base_link'].parent == 'r1_robotiq_ft_frame_id'


def test_two_prefixed_robots_in_one_model(tmp_path):
    cell = tmp_path / 'cell.xacro'
    cell.write_text(textwrap.dedent('''\
        <robot name="two_arm_cell" xmlns:xacro="http://wiki.ros.org/xacro">
          <xacro:include filename="$(find ur3_ft_gripper_description)/urdf/inc/ur3_ft_gripper_macro.xacro"/>
          <link name="world"/>
          <xacro:ur3_ft_gripper prefix="left_"/>
          <xacro:ur3_ft_gripper prefix="right_"/>
          <joint name="world-left" type="fixed"><parent link="world"/><child link="left_base_link"/>
            <origin xyz="0 0.4 0"/></joint>
          <joint name="world-right" type="fixed"><parent link="world"/><child link="right_base_link"/>
            <origin xyz="0 -0.4 0"/></joint>
        </robot>'''))
    text = description.to_xml(description.expand(str(cell)))
    model = ExpandedModel(text)
    single = ExpandedModel(description.to_xml(description.expand_model({})))
    assert model.root() == 'world'
    assert len(model.links) == 2 * len(single.links) + 1
    for side in ('left_', 'right_'):
        assert model.parent_joint[side + 'robotiq_arg2f_base_link'].parent == side + 'robotiq_ft_frame_id'
        np.testing.assert_allclose(
            model.transform(side + 'tool0', side + 'robotiq_arg2f_base_link'),
            single.transform('tool0', 'robotiq_arg2f_base_link'), atol=1e-9)
    urdf = tmp_path / 'cell.urdf'
    urdf.write_text(text)
    assert subprocess.run(['check_urdf', str(urdf)], stdout=subprocess.DEVNULL).returncode == 0

