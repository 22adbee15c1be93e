"""ur_type, the part toggles and world: what they accept, what they refuse, what they add."""
import os
import subprocess
import textwrap

import numpy as np
import pytest

from conftest import UR_CONFIG, UR_CONFIG_ROOT, UR_TYPES, ExpandedModel, assert_one_line_error, run_expand
from ur3_ft_gripper_description import description, kinematics

PARAMETER_FILES = ('joint_limits.yaml', 'default_kinematics.yaml', 'physical_parameters.yaml',
                   'visual_parameters.yaml')
VALID_LIST = ', '.join(UR_TYPES)


def test_ur_types_are_exactly_the_models_ur_description_ships():
    shipped = sorted(d for d in os.listdir(UR_CONFIG_ROOT)
                     if all(os.path.isfile(os.path.join(UR_CONFIG_ROOT, d, f)) for f in PARAMETER_FILES))
    assert sorted(UR_TYPES) == shipped
    assert set(UR_TYPES) == {'ur3', 'ur3e', 'ur5', 'ur5e', 'ur10', 'ur10e', 'ur16e', 'ur20', 'ur30'}


@pytest.mark.parametrize('ur_type', ['ur4', 'UR3', 'ur3 ', ''])
def test_unknown_ur_type_is_one_line_listing_the_valid_ones(ur_type):
    assert_one_line_error(run_expand('ur_type:=%s' % ur_type), 'ur_type', VALID_LIST)


def test_plain_xacro_on_the_macro_also_names_the_valid_ur_types(tmp_path):
    cell = tmp_path / 'cell.xacro'
    cell.write_text(textwrap.dedent('''\
        <robot name="cell" xmlns:xacro="http://wiki.ros.org/xacro">
          <xacro:include filename="$(find ur3_ft_gripper_description)/urdf/inc/ur3_ft_gripper_macro.xacro"/>
          <xacro:ur3_ft_gripper prefix="" ur_type="ur6"/>
        </robot>'''))
    with pytest.raises(description.DescriptionError) as error:
        description.run_xacro(str(cell))
    assert "ur_type 'ur6'" in str(error.value) and VALID_LIST in str(error.value)
    assert '\n' not in str(error.value)


@pytest.mark.parametrize('arg', ['ft_sensor', 'gripper', 'world'])
def test_toggle_that_is_not_a_boolean(arg):
    assert_one_line_error(run_expand('%s:=maybe' % arg), arg, 'true or %s:=false' % arg)


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
