"""The URScript pose functions against matrices built here, from the manual's definitions.

A pose p[x, y, z, rx, ry, rz] is the matrix [R p; 0 1] with R from the
rotation vector by Rodrigues' formula, written out below in numpy.
"""
import math

import numpy as np
import pytest

from ur3_ft_gripper_description.urscript import functions as f

POSES = [[0.4, -0.1, 0.2, 0.0, 0.0, 1.5707963], [0.05, 0.0, 0.1, 3.0, 0.1, -0.2],
         [-0.3, 0.25, 0.6, 0.5, -1.2, 0.7], [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]]
PAIRS = [(a, b) for a in POSES for b in POSES]


def rotation(rotvec):
    angle = np.linalg.norm(rotvec)
    if angle == 0:
        return np.eye(3)
    x, y, z = np.asarray(rotvec) / angle
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k.dot(k)


def matrix(pose):
    t = np.eye(4)
    t[:3, :3] = rotation(pose[3:])
    t[:3, 3] = pose[:3]
    return t


def same_pose(pose, t):
    return np.allclose(pose[:3], t[:3, 3], atol=1e-9) and np.allclose(rotation(pose[3:]), t[:3, :3], atol=1e-9)


@pytest.mark.parametrize('a, b', PAIRS)
def test_pose_trans_is_the_product_of_the_transforms(a, b):
    assert same_pose(f.pose_trans(a, b), matrix(a).dot(matrix(b)))


@pytest.mark.parametrize('a', POSES)
def test_pose_inv_is_the_inverse_transform(a):
    assert same_pose(f.pose_inv(a), np.linalg.inv(matrix(a)))
    assert same_pose(f.pose_trans(a, f.pose_inv(a)), np.eye(4))


@pytest.mark.parametrize('a, b', PAIRS)
def test_pose_add_adds_positions_and_composes_rotations_in_the_base_frame(a, b):
    expected = np.eye(4)
    expected[:3, :3] = rotation(a[3:]).dot(rotation(b[3:]))
    expected[:3, 3] = np.add(a[:3], b[:3])
    assert same_pose(f.pose_add(a, b), expected)


@pytest.mark.parametrize('a, b', PAIRS)
def test_pose_sub_undoes_pose_add(a, b):
    expected = np.eye(4)
    expected[:3, :3] = rotation(a[3:]).dot(rotation(b[3:]).T)
    expected[:3, 3] = np.subtract(a[:3], b[:3])
    assert same_pose(f.pose_sub(a, b), expected)
    assert same_pose(f.pose_add(f.pose_sub(a, b), b), matrix(a))


@pytest.mark.parametrize('a, b', PAIRS)
def test_interpolate_pose_runs_straight_and_turns_about_one_axis(a, b):
    assert same_pose(f.interpolate_pose(a, b, 0.0), matrix(a))
    assert same_pose(f.interpolate_pose(a, b, 1.0), matrix(b))
    half = f.interpolate_pose(a, b, 0.5)
    assert np.allclose(half[:3], (np.array(a[:3]) + b[:3]) / 2)
    # Halfway on the geodesic: the relative rotation is split into two equal halves.
    relative = rotation(a[3:]).T.dot(rotation(b[3:]))
    half_relative = rotation(a[3:]).T.dot(rotation(half[3:]))
    assert np.allclose(half_relative.dot(half_relative), relative, atol=1e-9)


@pytest.mark.parametrize('a, b', PAIRS)
def test_point_dist_and_pose_dist(a, b):
    assert f.point_dist(a, b) == pytest.approx(np.linalg.norm(np.subtract(a[:3], b[:3])))
    relative = rotation(a[3:]).T.dot(rotation(b[3:]))
    angle = math.acos(max(-1.0, min(1.0, (np.trace(relative) - 1) / 2)))
    assert f.pose_dist(a, b) == pytest.approx(math.hypot(f.point_dist(a, b), angle), abs=1e-9)


def rpy_matrix(roll, pitch, yaw):
    def rz(t):
        return np.array([[math.cos(t), -math.sin(t), 0], [math.sin(t), math.cos(t), 0], [0, 0, 1]])

    def ry(t):
        return np.array([[math.cos(t), 0, math.sin(t)], [0, 1, 0], [-math.sin(t), 0, math.cos(t)]])

    def rx(t):
        return np.array([[1, 0, 0], [0, math.cos(t), -math.sin(t)], [0, math.sin(t), math.cos(t)]])
    return rz(yaw).dot(ry(pitch)).dot(rx(roll))


@pytest.mark.parametrize('rpy', [[0.1, 0.2, 0.3], [3.0, -1.2, 0.5], [0.0, 0.0, -2.5], [-0.7, 1.0, 3.1]])
def test_rpy2rotvec_and_back_use_extrinsic_xyz(rpy):
    rotvec = f.rpy2rotvec(rpy)
    assert np.allclose(rotation(rotvec), rpy_matrix(*rpy), atol=1e-9)
    assert np.allclose(f.rotvec2rpy(rotvec), rpy, atol=1e-9)


def test_math_functions_follow_the_manual():
    assert f.PURE['atan2'][0](1.0, 0.0) == pytest.approx(math.pi / 2)  # atan2(x, y): arc tangent of x/y
    assert f.binary_list_to_integer([True, False, True]) == 5
    assert f.binary_list_to_integer(f.integer_to_binary_list(-7)) == -7
    assert f.integer_to_binary_list(6)[:4] == [False, True, True, False]
    assert f.PURE['floor'][0](-1.5) == -2 and f.PURE['ceil'][0](1.2) == 2
    assert f.log(2, 8) == pytest.approx(3) and f.norm(-3) == 3 and f.norm([3, 4]) == 5
    assert f.str_cat('x=', 1.5) == 'x=1.5' and f.str_cat(True, [1, 2]) == 'True[1, 2]'
    assert f.to_num('0x1F') == 31 and f.to_num(' -2.5') == -2.5 and f.str_sub('hello', 1, 3) == 'ell'
    with pytest.raises(f.RuntimeFault):
        f.sqrt(-1)
