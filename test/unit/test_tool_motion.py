"""URScript's motions (devices/ur_arm/tool_motion.py) against independent kinematics, without ROS.

Each motion is stepped at the robot's real period (ur3: CB3, 8 ms; ur5e:
e-Series, 2 ms) with a kinematic follower (the commanded joints are the
actual ones), on the real expanded model. The tool is measured by the
generic URDF chain of kinematics.Model (base -> tool0), not by the
ArmKinematics the motions use, and speeds by finite differences of it; the
expected times come from the trapezoid's own formulas written out here.
"""
import math

import numpy as np
import pytest

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices.ur_arm import tool_motion as tm
from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics
from ur3_ft_gripper_description.devices.ur_arm.cartesian import pose_from_ur_pose

JOINTS = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
          'wrist_3_joint']
PERIOD = {'ur3': 0.008, 'ur5e': 0.002}  # CB3 125 Hz, e-Series 500 Hz
# Elbow bent, tool down, away from the singularities; the moves below stay well inside each arm's reach.
START = np.array([0.3, -1.4, 1.6, -1.8, -1.57, 0.2])
# (m) a move the smaller arm makes comfortably from START.
MOVE = {'ur3': np.array([0.12, 0.06, -0.08]), 'ur5e': np.array([0.25, 0.1, -0.12])}
# A tool offset like the gripper's TCP: 0.2 m along tool0's z.
TCP = np.eye(4)
TCP[2, 3] = 0.2


class Cell(object):
    """One arm: the motions' kinematics and an independent forward kinematics to measure the tool with."""

    def __init__(self, text, ur_type):
        self.arm = ArmKinematics(text, JOINTS)
        self.model = kinematics.Model(text)
        self.ur_type = ur_type
        self.dt = PERIOD[ur_type]

    def tool(self, q, tcp=None):
        pose = self.model.transform('base', 'tool0', dict(zip(JOINTS, q)))
        return pose if tcp is None else pose.dot(tcp)


@pytest.fixture(params=['ur3', 'ur5e'])
def cell(request, configured_model):
    return Cell(configured_model(request.param, False, False).text, request.param)


def run(cell, motion, q, until='done', seconds=20.0, tcp=None):
    """Step `motion` until its `until` flag; (joints, tool poses) of every cycle, the start first."""
    joints, poses = [np.array(q, dtype=float)], [cell.tool(q, tcp)]
    for _ in range(int(seconds / cell.dt)):
        if getattr(motion, until):
            break
        q = motion.step(cell.dt, q, None)
        joints.append(q)
        poses.append(cell.tool(q, tcp))
    else:
        raise AssertionError('%s not %s within %g s' % (motion.name, until, seconds))
    return joints, poses


def positions(poses):
    return np.array([p[:3, 3] for p in poses])


def speeds(cell, poses):
    return np.diff(positions(poses), axis=0) / cell.dt


def distance_to_segment(points, a, b):
    direction = (b - a) / np.linalg.norm(b - a)
    along = np.clip((points - a).dot(direction), 0.0, np.linalg.norm(b - a))
    return np.linalg.norm(points - (a + along[:, None] * direction), axis=1)


def angle_between(r1, r2):
    return math.acos(max(-1.0, min(1.0, (np.trace(r1.T.dot(r2)) - 1.0) / 2.0)))


def trapezoid_time(distance, v, a):
    """Time of a rest-to-rest move over `distance` with peak speed v and acceleration a."""
    return distance / v + v / a if distance >= v * v / a else 2.0 * math.sqrt(distance / a)


def rotation_about(axis, angle):
    return pose_from_ur_pose([0.0, 0.0, 0.0] + list(np.asarray(axis, dtype=float) / np.linalg.norm(axis) * angle))


# -- movel ---------------------------------------------------------------------------------------------

def test_movel_is_straight_keeps_its_speed_and_ends_on_target(cell):
    start = cell.tool(START, TCP)
    target = start.copy()
    target[:3, 3] += MOVE[cell.ur_type]
    target = target.dot(rotation_about([1.0, 1.0, 0.0], 0.2))  # turned too: slerped in step
    motion = tm.LinearMove(cell.arm, TCP, START, None, target)
    joints, poses = run(cell, motion, START, tcp=TCP)
    points = positions(poses)
    assert np.max(distance_to_segment(points, start[:3, 3], target[:3, 3])) < 1e-3
    assert np.linalg.norm(points[-1] - target[:3, 3]) < 5e-4
    assert math.degrees(angle_between(poses[-1][:3, :3], target[:3, :3])) < 0.1
    # Orientation in step with position: the share turned is the share travelled.
    length = np.linalg.norm(target[:3, 3] - start[:3, 3])
    for pose in poses[::10]:
        travelled = np.linalg.norm(pose[:3, 3] - start[:3, 3]) / length
        assert abs(angle_between(start[:3, :3], pose[:3, :3]) / 0.2 - travelled) < 0.01
    peak = np.max(np.linalg.norm(speeds(cell, poses), axis=1))
    assert abs(peak - tm.MOVEL_V) < 0.02 * tm.MOVEL_V
    took = (len(poses) - 1) * cell.dt
    assert abs(took - trapezoid_time(length, tm.MOVEL_V, tm.MOVEL_A)) <= 1.5 * cell.dt
    assert motion.returned and motion.done


def test_a_pure_rotation_turns_at_four_radians_a_second_per_metre_a_second(cell):
    start = cell.tool(START, TCP)
    target = start.dot(rotation_about([0.0, 0.0, 1.0], 0.8))
    motion = tm.LinearMove(cell.arm, TCP, START, None, target, v=0.1, a=0.5)
    _, poses = run(cell, motion, START, tcp=TCP)
    assert np.max(np.linalg.norm(positions(poses) - start[:3, 3], axis=1)) < 5e-4
    assert math.degrees(angle_between(poses[-1][:3, :3], target[:3, :3])) < 0.1
    rates = [angle_between(p[:3, :3], n[:3, :3]) / cell.dt for p, n in zip(poses, poses[1:])]
    assert abs(max(rates) - 4.0 * 0.1) < 0.02 * 0.4
    assert abs((len(poses) - 1) * cell.dt - trapezoid_time(0.8, 0.4, 2.0)) <= 1.5 * cell.dt


def test_movel_with_t_takes_t(cell):
    start = cell.tool(START)
    target = start.copy()
    target[:3, 3] += MOVE[cell.ur_type] * 0.5
    motion = tm.LinearMove(cell.arm, None, START, None, target, t=3.0)
    _, poses = run(cell, motion, START)
    assert abs((len(poses) - 1) * cell.dt - 3.0) <= 1.5 * cell.dt
    assert np.linalg.norm(positions(poses)[-1] - target[:3, 3]) < 5e-4


def test_an_unreachable_movel_target_is_refused_before_moving_with_one_line(cell):
    target = cell.tool(START)
    target[:3, 3] = [2.5, 0.0, 0.3]
    with pytest.raises(tm.MotionError) as error:
        tm.LinearMove(cell.arm, None, START, None, target)
    assert '\n' not in str(error.value) and 'out of reach' in str(error.value)


# -- blends ----------------------------------------------------------------------------------------------

def blended_run(cell, first, build_second, q, tcp=None):
    """Run `first` until it returns, then the second (built from it) to its end: joints, poses, the
    index where the second began, the second."""
    joints, poses = run(cell, first, q, until='returned', tcp=tcp)
    second = build_second(first)
    more_joints, more_poses = run(cell, second, joints[-1], tcp=tcp)
    return joints + more_joints[1:], poses + more_poses[1:], len(poses) - 1, second


def test_two_movel_blend_within_r_of_the_corner_with_continuous_speed(cell):
    r = 0.02
    start = cell.tool(START, TCP)
    corner, end = start.copy(), start.copy()
    corner[:3, 3] += [0.1, 0.0, 0.0]
    end[:3, 3] += [0.1, 0.1, 0.0]
    first = tm.LinearMove(cell.arm, TCP, START, None, corner, r=r)
    joints, poses, switch, second = blended_run(
        cell, first, lambda m: tm.LinearMove(cell.arm, TCP, None, None, end, previous=m), START, TCP)
    points = positions(poses)
    assert np.linalg.norm(points[switch] - corner[:3, 3]) <= r + 1e-9  # returned within r
    assert not np.linalg.norm(points[switch - 1] - corner[:3, 3]) <= r  # ... on entering it
    off_lines = np.minimum(distance_to_segment(points, start[:3, 3], corner[:3, 3]),
                           distance_to_segment(points, corner[:3, 3], end[:3, 3])) > 1e-3
    assert off_lines.any()  # a blend, not a stop at the corner
    assert np.all(np.linalg.norm(points[off_lines] - corner[:3, 3], axis=1) <= r + 1e-4)
    assert np.min(np.linalg.norm(points - corner[:3, 3], axis=1)) > 1e-3  # the corner is cut
    velocity = speeds(cell, poses)
    assert np.max(np.linalg.norm(velocity, axis=1)) <= tm.MOVEL_V * 1.02
    # Continuous: no cycle changes the tool's velocity by more than the acceleration allows.
    assert np.max(np.linalg.norm(np.diff(velocity, axis=0), axis=1)) <= 2.0 * tm.MOVEL_A * cell.dt + 1e-3
    assert np.linalg.norm(points[-1] - end[:3, 3]) < 5e-4
    assert second.done


def test_two_movej_blend_and_end_on_the_second_target(cell):
    middle = START + np.array([0.4, 0.1, -0.1, 0.0, 0.0, 0.3])
    last = middle + np.array([0.0, 0.3, 0.2, 0.2, 0.0, 0.0])
    first = tm.JointMove(cell.arm, START, None, middle, r=0.05)
    joints, poses, switch, second = blended_run(
        cell, first, lambda m: tm.JointMove(cell.arm, None, None, last, previous=m), START)
    assert np.linalg.norm(positions(poses)[switch] - cell.tool(middle)[:3, 3]) <= 0.05 + 1e-9
    assert np.max(np.abs(joints[-1] - last)) < 1e-9
    joint_speeds = np.diff(np.array(joints), axis=0) / cell.dt
    assert np.max(np.abs(joint_speeds)) <= tm.MOVEJ_V * 1.001
    assert np.max(np.abs(np.diff(joint_speeds, axis=0))) <= 2.0 * tm.MOVEJ_A * cell.dt + 1e-9


def test_two_movep_turn_through_an_arc_inside_r(cell):
    r = 0.03
    start = cell.tool(START, TCP)
    corner, end = start.copy(), start.copy()
    corner[:3, 3] += [0.12, 0.0, 0.0]
    end[:3, 3] += [0.12, 0.0, -0.1]
    first = tm.ProcessMove(cell.arm, TCP, START, None, corner, v=0.15, r=r)
    joints, poses, switch, second = blended_run(
        cell, first, lambda m: tm.ProcessMove(cell.arm, TCP, None, None, end, v=0.15, previous=m), START, TCP)
    assert second.arc is not None
    points = positions(poses)
    off_lines = np.minimum(distance_to_segment(points, start[:3, 3], corner[:3, 3]),
                           distance_to_segment(points, corner[:3, 3], end[:3, 3])) > 1e-3
    assert off_lines.any()
    assert np.all(np.linalg.norm(points[off_lines] - corner[:3, 3], axis=1) <= r + 1e-4)
    # Constant tool speed through the arc (v = 0.15 is reached before the blend: r > v^2 / 2a).
    arc_speeds = np.linalg.norm(speeds(cell, poses), axis=1)[np.nonzero(off_lines)[0][:-1]]
    assert np.all(np.abs(arc_speeds - 0.15) < 0.02 * 0.15)
    assert np.linalg.norm(points[-1] - end[:3, 3]) < 5e-4


# -- speedl, stopl ---------------------------------------------------------------------------------------

def test_speedl_reaches_the_tool_speed_then_stopl_stops_within_v2_over_2a(cell):
    xd = np.array([0.06, -0.04, 0.03, 0.0, 0.0, 0.0])
    a = 0.5
    motion = tm.ToolSpeed(cell.arm, TCP, START, None, xd, a)
    joints, poses = run(cell, motion, START, until='returned', tcp=TCP)
    speed = float(np.linalg.norm(xd[:3]))
    assert abs((len(poses) - 1) * cell.dt - speed / a) <= 1.5 * cell.dt  # returns on reaching it
    more_joints, more_poses = run(cell, motion, joints[-1], until='reached', seconds=0.2, tcp=TCP)
    for _ in range(int(0.2 / cell.dt)):
        more_joints.append(motion.step(cell.dt, more_joints[-1], None))
        more_poses.append(cell.tool(more_joints[-1], TCP))
    velocity = speeds(cell, more_poses)[-1]
    assert abs(np.linalg.norm(velocity) - speed) < 0.02 * speed
    assert np.dot(velocity, xd[:3]) / (np.linalg.norm(velocity) * speed) > 0.9995
    # The orientation holds: no angular speed was asked for.
    assert math.degrees(angle_between(poses[0][:3, :3], more_poses[-1][:3, :3])) < 0.05
    stop = tm.ToolStop(cell.arm, TCP, None, None, a, previous=motion)
    stop_joints, stop_poses = run(cell, stop, more_joints[-1], tcp=TCP)
    travelled = np.linalg.norm(stop_poses[-1][:3, 3] - stop_poses[0][:3, 3])
    assert abs(travelled - speed ** 2 / (2.0 * a)) < 0.02 * speed ** 2 / (2.0 * a) + 1e-4
    assert abs((len(stop_poses) - 1) * cell.dt - speed / a) <= 1.5 * cell.dt
    assert np.linalg.norm(speeds(cell, stop_poses)[-1]) <= a * cell.dt  # the last cycle's mean speed


def test_speedl_turns_the_tool_at_the_angular_speed(cell):
    xd = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.4])
    motion = tm.ToolSpeed(cell.arm, TCP, START, None, xd, 1.0, t=0.8)
    joints, poses = run(cell, motion, START, until='returned', tcp=TCP)
    assert abs((len(poses) - 1) * cell.dt - 0.8) <= 1.5 * cell.dt  # t given: returns after t
    turn = pose_from_ur_pose([0, 0, 0] + list(tm.ur_pose_of(poses[-1].dot(np.linalg.inv(poses[-2])))[3:]))
    rate = tm.ur_pose_of(turn)[3:]
    assert np.allclose(np.array(rate) / cell.dt, xd[3:], atol=0.02 * 0.4)
    assert np.max(np.linalg.norm(positions(poses) - poses[0][:3, 3], axis=1)) < 5e-4


def test_speedl_beyond_the_joints_speed_limits_is_scaled_down_in_the_same_direction(cell):
    xd = np.array([0.0, 0.0, -3.0, 0.0, 0.0, 0.0])
    motion = tm.ToolSpeed(cell.arm, None, START, None, xd, 20.0)
    joints, poses = [START], [cell.tool(START)]
    for _ in range(int(0.2 / cell.dt)):
        joints.append(motion.step(cell.dt, joints[-1], None))
        poses.append(cell.tool(joints[-1]))
    assert np.all(np.abs(np.diff(np.array(joints), axis=0)) / cell.dt <= cell.arm.velocity * (1.0 + 1e-3))
    velocity = speeds(cell, poses)[-1]
    assert velocity[2] < -0.1 and np.linalg.norm(velocity[:2]) < 0.01 * abs(velocity[2])


def test_speedl_t_min_of_older_software_waits_for_the_speed(cell):
    motion = tm.ToolSpeed(cell.arm, None, START, None, [0.05, 0, 0, 0, 0, 0], 0.1, t=0.1, minimum_time=True)
    joints, _ = run(cell, motion, START, until='returned')
    assert abs((len(joints) - 1) * cell.dt - 0.5) <= 1.5 * cell.dt


# -- speedj, stopj, servoj -----------------------------------------------------------------------------

def test_speedj_then_stopj(cell):
    qd = np.array([0.2, -0.1, 0.0, 0.0, 0.0, 0.3])
    motion = tm.JointSpeed(cell.arm, START, None, qd, 1.0, t=0.5)
    joints, _ = run(cell, motion, START, until='returned')
    assert abs((len(joints) - 1) * cell.dt - 0.5) <= 1.5 * cell.dt
    assert np.allclose(motion.qd, qd)
    stop = tm.JointStop(cell.arm, None, None, 2.0, previous=motion)
    stop_joints, _ = run(cell, stop, joints[-1])
    assert abs((len(stop_joints) - 1) * cell.dt - 0.3 / 2.0) <= 1.5 * cell.dt
    # The leading joint's stopping distance, v^2 / 2a.
    assert abs((stop_joints[-1] - stop_joints[0])[5] - 0.3 ** 2 / 4.0) < 1e-3


def test_speedj_into_a_joint_limit_stops_the_motion_with_one_line(cell):
    q = START.copy()
    q[5] = cell.arm.upper[5] - 0.05
    motion = tm.JointSpeed(cell.arm, q, None, [0, 0, 0, 0, 0, 1.0], 5.0)
    with pytest.raises(tm.MotionError) as error:
        run(cell, motion, q, until='done', seconds=1.0)
    assert '\n' not in str(error.value) and 'limit' in str(error.value)


def test_servoj_follows_with_its_lookahead_time(cell):
    target = START + 0.05
    q, motion = START, None
    steps = int(round(0.1 / cell.dt))  # one lookahead time
    for _ in range(steps):
        motion = tm.Servo(cell.arm, q, None, target, t=cell.dt, previous=motion)
        q = motion.step(cell.dt, q, None)
        assert motion.returned and motion.done
    assert np.allclose(q - START, 0.05 * (1.0 - math.exp(-steps * cell.dt / tm.SERVOJ_LOOKAHEAD_TIME)), rtol=1e-6)


# -- movej ---------------------------------------------------------------------------------------------

def test_movej_ends_on_target_in_the_trapezoid_time(cell):
    target = START + np.array([0.8, 0.2, -0.3, 0.1, 0.0, -0.5])
    motion = tm.JointMove(cell.arm, START, None, target)
    joints, _ = run(cell, motion, START)
    assert np.max(np.abs(joints[-1] - target)) < 1e-12
    assert abs((len(joints) - 1) * cell.dt - trapezoid_time(0.8, tm.MOVEJ_V, tm.MOVEJ_A)) <= 1.5 * cell.dt
    # All joints start and stop together: the path is a straight line in joint space.
    moving = target != START
    shares = (np.array(joints) - START)[:, moving] / (target - START)[moving]
    assert np.allclose(shares, shares[:, :1])


def test_movej_with_t_takes_t(cell):
    target = START + np.array([0.3, 0.0, 0.0, 0.0, 0.0, 0.0])
    motion = tm.JointMove(cell.arm, START, None, target, t=4.0)
    joints, _ = run(cell, motion, START)
    assert abs((len(joints) - 1) * cell.dt - 4.0) <= 1.5 * cell.dt
    assert np.max(np.abs(joints[-1] - target)) < 1e-12


def test_movej_beyond_the_joint_limits_is_refused_with_one_line(cell):
    target = START.copy()
    target[1] = cell.arm.upper[1] + 0.5
    with pytest.raises(tm.MotionError) as error:
        tm.JointMove(cell.arm, START, None, target)
    assert '\n' not in str(error.value) and 'limit' in str(error.value)


# -- poses -------------------------------------------------------------------------------------------------

def test_ur_pose_of_is_the_inverse_of_pose_from_ur_pose(cell):
    pose = tm.tcp_pose(cell.arm, TCP, START)
    assert np.allclose(pose, cell.tool(START, TCP), atol=1e-9)
    assert np.allclose(pose_from_ur_pose(tm.ur_pose_of(pose)), pose, atol=1e-12)
