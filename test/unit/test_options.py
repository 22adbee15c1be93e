"""ur_type, the part toggles and world: what they accept, what they refuse, what they add."""
import os
import shutil
import subprocess
import textwrap

import numpy as np
import pytest
import rospkg
import yaml
from roslaunch.substitution_args import resolve_args

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.model import description
from ur3_ft_gripper_testing.model import (UR_CONFIG, UR_CONFIG_ROOT, UR_TYPES, ExpandedModel, assert_one_line_error,
                                          run_expand)

PARAMETER_FILES = tuple(description.UR_DEFAULT_FILES.values())
VALID_LIST = ', '.join(UR_TYPES)
PINNED_UR_TYPES = ['ur3', 'ur3e', 'ur5', 'ur5e', 'ur10', 'ur10e', 'ur16e', 'ur20', 'ur30']  # 1.3.2


def test_ur_types_are_the_models_the_pinned_ur_description_ships():
    assert UR_TYPES == PINNED_UR_TYPES


@pytest.fixture
def ur_description_with_ur7e(tmp_path):
    """ROS_PACKAGE_PATH with a ur_description whose config/ also has a 'ur7e' (ur5e's files).

    The copy holds links to the installed package's files and a config folder
    of its own, in the test's temporary folder, ahead of the installed one.
    """
    installed = rospkg.RosPack().get_path('ur_description')
    copy = tmp_path / 'ur_description'
    copy.mkdir()
    for name in os.listdir(installed):
        if name != 'config':
            os.symlink(os.path.join(installed, name), str(copy / name))
    shutil.copytree(os.path.join(installed, 'config'), str(copy / 'config'))
    shutil.copytree(str(copy / 'config' / 'ur5e'), str(copy / 'config' / 'ur7e'))
    env = dict(os.environ, ROS_PACKAGE_PATH=os.pathsep.join([str(tmp_path), os.environ['ROS_PACKAGE_PATH']]))
    assert rospkg.RosPack(rospkg.get_ros_paths(env)).get_path('ur_description') == str(copy)
    return env


def test_a_model_that_the_installed_ur_description_adds_works(ur_description_with_ur7e, tmp_path):
    run = run_expand('ur_type:=ur7e', '-o', str(tmp_path / 'ur7e.urdf'), env=ur_description_with_ur7e)
    assert run.returncode == 0, run.stderr
    model = ExpandedModel((tmp_path / 'ur7e.urdf').read_text())
    ur5e = os.path.join(UR_CONFIG_ROOT, 'ur5e', 'default_kinematics.yaml')
    with open(ur5e) as f:
        shoulder_height = yaml.safe_load(f)['kinematics']['shoulder']['z']
    assert model.origin_xyz('shoulder_pan_joint')[2] == pytest.approx(shoulder_height)
    model.assert_joint_between('robotiq_ft_frame_id', 'robotiq_arg2f_base_link', 'fixed')


def test_the_load_launch_takes_a_model_that_the_installed_ur_description_adds(ur_description_with_ur7e):
    run = subprocess.run(['roslaunch', '--dump-params', 'ur3_ft_gripper_description',
                          'load_ur_ft_gripper.launch', 'ur_type:=ur7e'],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                         env=ur_description_with_ur7e, timeout=120)
    assert run.returncode == 0 and 'expand_description: error' not in run.stderr, run.stderr
    assert '/robot_description' in run.stdout and 'robotiq_arg2f_base_link' in run.stdout


def test_unknown_ur_type_lists_what_the_installed_ur_description_ships(ur_description_with_ur7e):
    run = run_expand('ur_type:=ur4', env=ur_description_with_ur7e)
    assert_one_line_error(run, os.path.join('config', 'ur4', 'joint_limits.yaml'),
                          'installed ur_description has the models', 'ur5e, ur7e, ur10')


@pytest.mark.parametrize('ur_type', ['ur4', 'UR3', 'ur3 ', ''])
def test_unknown_ur_type_is_one_line_listing_the_valid_ones(ur_type):
    # xacro names the file it lacks; the line adds the models there are.
    assert_one_line_error(run_expand('ur_type:=%s' % ur_type), 'No such file', 'has the models', VALID_LIST)


def _cell_with_ur_type(tmp_path, ur_type):
    cell = tmp_path / 'cell.xacro'
    cell.write_text(textwrap.dedent('''\
        <robot name="cell" xmlns:xacro="http://wiki.ros.org/xacro">
          <xacro:include filename="$(find ur3_ft_gripper_description)/urdf/inc/ur3_ft_gripper_macro.xacro"/>
          <xacro:ur3_ft_gripper prefix="" ur_type="%s"/>
        </robot>''' % ur_type))
    return str(cell)


def test_expand_description_on_a_cell_names_the_valid_ur_types(tmp_path):
    assert_one_line_error(run_expand(_cell_with_ur_type(tmp_path, 'ur6')),
                          os.path.join('config', 'ur6', 'joint_limits.yaml'), VALID_LIST)


def test_plain_xacro_on_a_cell_names_the_missing_model_folder(tmp_path):
    # xacro cannot list ur_description's models; its own error names the folder it lacks.
    run = subprocess.run([resolve_args('$(find xacro)/xacro'), _cell_with_ur_type(tmp_path, 'ur6')],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, timeout=120)
    assert run.returncode != 0
    assert 'No such file or directory' in run.stderr
    assert os.path.join('ur_description', 'config', 'ur6', 'joint_limits.yaml') in run.stderr


@pytest.mark.parametrize('arg', ['ft_sensor', 'gripper', 'world'])
def test_toggle_that_is_not_a_boolean(arg):
    # xacro's own words: the condition and the value it refused.
    assert_one_line_error(run_expand('%s:=maybe' % arg), '"maybe"', 'not a boolean')


def test_explicit_parameter_file_wins_over_the_ur_type_default(expand_model):
    ur3_kinematics = os.path.join(UR_CONFIG, 'default_kinematics.yaml')
    model = expand_model(ur_type='ur5e', kinematics_params=ur3_kinematics)
    assert model.origin_xyz('shoulder_pan_joint')[2] == pytest.approx(0.1519)  # UR3's
    assert expand_model(ur_type='ur5e').origin_xyz('shoulder_pan_joint')[2] == pytest.approx(0.1625)


@pytest.mark.parametrize('prefix', ['', 'r1_'])
def test_world_roots_the_model_at_world(expand_model, prefix, tmp_path):
    model = expand_model(world='true', prefix=prefix)
    assert model.root() == 'world'
    joint = model.assert_joint_between('world', prefix + 'base_link', 'fixed')
    assert joint.name == prefix + 'world_joint'
    np.testing.assert_allclose(kinematics.pose_matrix(joint.origin), np.eye(4))
    urdf = tmp_path / 'world.urdf'
    urdf.write_text(model.text)
    run = subprocess.run(['check_urdf', str(urdf)], stdout=subprocess.PIPE, universal_newlines=True)
    assert run.returncode == 0 and 'root Link: world' in run.stdout


def test_world_with_the_ur_and_ft300_of_the_second_blog_post(expand_model):
    model = expand_model(world='true', gripper='false')
    assert model.root() == 'world'
    chain = model.path_to_root('robotiq_ft_frame_id')
    assert chain[:4] == ['robotiq_ft_frame_id', 'ft300_sensor', 'ft300_mounting_plate', 'tool0']
    assert chain[-2:] == ['base_link', 'world']
    assert not [lk for lk in model.links if 'robotiq_arg2f' in lk or 'finger' in lk]


def test_coupling_is_13_9_mm_and_keeps_the_gripper_turned_as_on_the_sensor(configured_model):
    bare = configured_model('ur3', False, True)
    on_sensor = configured_model('ur3', True, True)
    coupling = bare.transform('tool0', 'robotiq_arg2f_base_link')
    sensor = on_sensor.transform('tool0', 'robotiq_arg2f_base_link')
    np.testing.assert_allclose(coupling[:3, 3], [0, 0, 0.0139], atol=1e-9)
    np.testing.assert_allclose(coupling[:3, :3], sensor[:3, :3], atol=1e-9)
    mesh = bare.meshes('robotiq_arg2f_coupling')[0]
    assert mesh.filename == \
        'package://robotiq_2f_140_gripper_visualization/meshes/visual/robotiq_arg2f_coupling.stl'
    assert mesh.scale == [0.001, 0.001, 0.001]  # the STL is in mm
    bare.assert_mesh_resolves(mesh)


def test_both_parts_off_is_the_bare_ur_arm(configured_model):
    model = configured_model('ur5e', False, False)
    upstream = ExpandedModel(description.to_xml(description.run_xacro(
        os.path.join(os.path.dirname(UR_CONFIG_ROOT), 'urdf', 'ur.xacro'),
        {'robot_model': 'ur5e', **{arg: os.path.join(UR_CONFIG_ROOT, 'ur5e', f) for arg, f in zip(
            ('joint_limit_params', 'kinematics_params', 'physical_params', 'visual_params'),
            PARAMETER_FILES)}})))
    assert sorted(model.links) == sorted(upstream.links)
    assert sorted(model.joints) == sorted(upstream.joints)
    for link in upstream.links:
        np.testing.assert_allclose(model.to_root(link), upstream.to_root(link), atol=1e-12)
