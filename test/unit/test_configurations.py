"""Every ur_type x {FT 300 on/off} x {2F-140 on/off}, expanded once each and checked."""
import os
import subprocess

import numpy as np
import pytest
import yaml

from ur3_ft_gripper_description.model import tcp
from ur3_ft_gripper_testing.model import CONFIGURATIONS, UR_CONFIG_ROOT, configuration_id

ARM_CHAIN = ['base_link', 'base_link_inertia', 'shoulder_link', 'upper_arm_link', 'forearm_link',
             'wrist_1_link', 'wrist_2_link', 'wrist_3_link', 'flange', 'tool0']
SENSOR_LINKS = ['ft300_mounting_plate', 'ft300_sensor', 'robotiq_ft_frame_id']
GRIPPER_LINKS = ['robotiq_arg2f_base_link', 'left_inner_finger_pad', 'right_inner_finger_pad', 'gripper_tcp']
COUPLING = 'robotiq_arg2f_coupling'
# tool0 -> robotiq_arg2f_base_link along the flange axis: the upstream FT 300
# macro's 41.5 mm, or the coupling's 13.9 mm (config/mounting.yaml).
MOUNT_HEIGHT = {True: 0.0415, False: 0.0139}

pytestmark = pytest.mark.parametrize('config', CONFIGURATIONS, ids=configuration_id)


def model_of(configured_model, config):
    return configured_model(config['ur_type'], config['ft_sensor'], config['gripper'])


def test_check_urdf_accepts_it_with_one_root(configured_model, config, tmp_path):
    model = model_of(configured_model, config)
    urdf = tmp_path / 'model.urdf'
    urdf.write_text(model.text)
    run = subprocess.run(['check_urdf', str(urdf)], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, universal_newlines=True)
    assert run.returncode == 0, run.stdout
    assert 'root Link: base_link' in run.stdout
    assert model.root() == 'base_link'
    model.assert_lacks_link('world')


def test_links_present_exactly_for_the_parts_chosen(configured_model, config):
    model = model_of(configured_model, config)
    assert len(model.links) == len(set(model.links))
    assert set(ARM_CHAIN) <= set(model.links)
    for link in SENSOR_LINKS:
        assert (link in model.links) == config['ft_sensor'], link
    for link in GRIPPER_LINKS:
        assert (link in model.links) == config['gripper'], link
    assert (COUPLING in model.links) == (config['gripper'] and not config['ft_sensor'])
    assert model.links.count('base_link') == 1  # the fork's extra base_link is gone


def test_chain_from_tool0(configured_model, config):
    model = model_of(configured_model, config)
    for parent, child in zip(ARM_CHAIN[7:], ARM_CHAIN[8:]):
        model.assert_joint_between(parent, child)
    chain = ['tool0']
    if config['ft_sensor']:
        chain += SENSOR_LINKS
    elif config['gripper']:
        chain += [COUPLING]
    if config['gripper']:
        chain += ['robotiq_arg2f_base_link', 'gripper_tcp']
    for parent, child in zip(chain, chain[1:]):
        model.assert_joint_between(parent, child, 'fixed')
    leaves = set(model.links) - {j.parent for j in model.joints.values()}
    assert chain[-1] in leaves


def test_arm_is_the_ur_type_from_its_own_parameter_files(configured_model, config):
    model = model_of(configured_model, config)
    folder = os.path.join(UR_CONFIG_ROOT, config['ur_type'])
    with open(os.path.join(folder, 'default_kinematics.yaml')) as f:
        kin = yaml.safe_load(f)['kinematics']
    assert model.origin_xyz('shoulder_pan_joint')[2] == pytest.approx(kin['shoulder']['z'])
    assert model.origin_xyz('elbow_joint')[0] == pytest.approx(kin['forearm']['x'])
    assert model.origin_xyz('wrist_1_joint')[0] == pytest.approx(kin['wrist_1']['x'])
    with open(os.path.join(folder, 'visual_parameters.yaml')) as f:
        base_mesh = yaml.safe_load(f)['mesh_files']['base']['visual']['mesh']
    assert model.meshes('base_link_inertia')[0].filename == base_mesh  # (the ur16e reuses the ur10e's meshes)


def test_tcp_sits_between_the_closed_pads_on_the_flange_axis(configured_model, config):
    model = model_of(configured_model, config)
    if not config['gripper']:
        model.assert_lacks_link('gripper_tcp')
        return
    pose = model.transform('tool0', 'gripper_tcp')
    with open(os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'gripper_tcp.yaml')) as f:
        tcp_z = yaml.safe_load(f)[tcp.YAML_KEY]['z']
    height = MOUNT_HEIGHT[config['ft_sensor']] + tcp_z
    np.testing.assert_allclose(pose[:3, 3], [0, 0, height], atol=1e-6)
    np.testing.assert_allclose(pose[:3, 2], [0, 0, 1], atol=1e-6)  # approach = flange axis
    # The gripper (and so the TCP's x) is turned the same way with or without the sensor.
    np.testing.assert_allclose(pose[:3, 0], [-1, 0, 0], atol=1e-6)
    # And it is where the closed pads meet, by this model's own forward kinematics.
    closed = {'finger_joint': model.limits('finger_joint')[1]}
    pads = [model.transform('gripper_tcp', pad, closed)[:3, 3]
            for pad in ('left_inner_finger_pad', 'right_inner_finger_pad')]
    np.testing.assert_allclose((pads[0] + pads[1]) / 2, 0.0, atol=1e-6)
    assert pads[0][0] < 0 < pads[1][0]  # x runs from the left pad to the right one
