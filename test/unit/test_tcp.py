"""config/gripper_tcp.yaml is what the gripper's kinematics say, for the robotiq layout installed."""
import os

import numpy as np
import pytest
import yaml

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.model import tcp
from ur3_ft_gripper_testing.model import PACKAGE_DIR, robotiq_variant

TCP_YAML = os.path.join(PACKAGE_DIR, 'config', 'gripper_tcp.yaml')


def stored_pose():
    with open(TCP_YAML) as f:
        return yaml.safe_load(f)[tcp.YAML_KEY]


def test_yaml_matches_the_tcp_recomputed_from_the_expanded_model(default_model):
    computed = tcp.tcp_pose(default_model.text)
    stored = stored_pose()
    for key in ('x', 'y', 'z'):
        assert stored[key] == pytest.approx(computed[key], abs=1e-6), (key, robotiq_variant())
    for key in ('roll', 'pitch', 'yaw'):
        assert stored[key] == pytest.approx(computed[key], abs=1e-6), (key, robotiq_variant())


def test_tcp_frame_in_the_model_is_the_computed_one(default_model):
    np.testing.assert_allclose(default_model.transform('robotiq_arg2f_base_link', 'gripper_tcp'),
                               tcp.tcp_matrix(default_model), atol=1e-6)


def test_tcp_is_about_0_2_m_out_on_the_gripper_axis(default_model):
    pose = default_model.transform('robotiq_arg2f_base_link', 'gripper_tcp')
    np.testing.assert_allclose(pose[:2, 3], 0.0, atol=1e-9)
    assert 0.195 < pose[2, 3] < 0.205
    np.testing.assert_allclose(pose[:3, 2], [0, 0, 1], atol=1e-9)


@pytest.mark.parametrize('angle', [0.0, 0.35, 0.7])
def test_fingers_close_along_tcp_x(default_model, angle):
    """The pads lie on the TCP's x axis, left at -x and right at +x, closing towards 0."""
    positions = {'finger_joint': angle}
    left = default_model.transform('gripper_tcp', 'left_inner_finger_pad', positions)[:3, 3]
    right = default_model.transform('gripper_tcp', 'right_inner_finger_pad', positions)[:3, 3]
    assert left[0] < 0 < right[0]
    np.testing.assert_allclose(left[1], 0.0, atol=1e-9)
    np.testing.assert_allclose(left[0], -right[0], atol=1e-9)


def test_mean_pose_refuses_models_that_disagree():
    a = dict(x=0, y=0, z=0.2, roll=0, pitch=0, yaw=0)
    assert tcp.mean_pose([a, dict(a, z=0.200001)])['z'] == pytest.approx(0.2000005)
    with pytest.raises(ValueError, match='disagree'):
        tcp.mean_pose([a, dict(a, z=0.21)])


@pytest.mark.parametrize('rpy', [(0, 0, 0), (0.3, -0.2, 1.1), (-2.5, 1.2, -0.4), (0, 0, np.pi / 2)])
def test_matrix_rpy_inverts_rpy_matrix(rpy):
    np.testing.assert_allclose(kinematics.matrix_rpy(kinematics.rpy_matrix(*rpy)), rpy, atol=1e-12)
