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


def off_the_lines(points, start, corner, end, tolerance):
    """Which points are further than `tolerance` from both lines, start -> corner and corner -> end (4x4 poses)."""
    return np.minimum(distance_to_segment(points, start[:3, 3], corner[:3, 3]),
                      distance_to_segment(points, corner[:3, 3], end[:3, 3])) > tolerance


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
    off_lines = off_the_lines(points, start, corner, end, 1e-3)
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
    off_lines = off_the_lines(points, start, corner, end, 1e-3)
    assert off_lines.any()
    assert np.all(np.linalg.norm(points[off_lines] - corner[:3, 3], axis=1) <= r + 1e-4)
    # Constant tool speed through the arc (v = 0.15 is reached before the blend: r > v^2 / 2a).
    arc_speeds = np.linalg.norm(speeds(cell, poses), axis=1)[np.nonzero(off_lines)[0][:-1]]
    assert np.all(np.abs(arc_speeds - 0.15) < 0.02 * 0.15)
    assert np.linalg.norm(points[-1] - end[:3, 3]) < 5e-4


def test_a_movel_blend_wider_than_the_stopping_distance_starts_when_the_first_has_its_ramp_left(cell):
    # r = 0.05 > v^2 / 2a: the first move is still at v on entering r, so the second waits (superposed
    # earlier, the two speeds add up beyond v and the path leaves the first line outside r).
    r = 0.05
    start = cell.tool(START, TCP)
    corner, end = start.copy(), start.copy()
    corner[:3, 3] += [0.1, 0.0, 0.0]
    end[:3, 3] += [0.1, 0.1, 0.0]
    first = tm.LinearMove(cell.arm, TCP, START, None, corner, r=r)
    joints, poses, switch, second = blended_run(
        cell, first, lambda m: tm.LinearMove(cell.arm, TCP, None, None, end, previous=m), START, TCP)
    points = positions(poses)
    off_lines = off_the_lines(points, start, corner, end, 1e-4)
    assert off_lines.any()
    assert np.all(np.linalg.norm(points[off_lines] - corner[:3, 3], axis=1) <= r + 1e-4)
    assert np.max(np.linalg.norm(speeds(cell, poses), axis=1)) <= tm.MOVEL_V * 1.02
    # The first move alone, then both together for its deceleration: the trapezoid's time plus the second's
    # own time less the overlap of one ramp.
    took = (len(poses) - 1) * cell.dt
    alone = trapezoid_time(0.1, tm.MOVEL_V, tm.MOVEL_A)
    assert abs(took - (2.0 * alone - tm.MOVEL_V / tm.MOVEL_A)) <= 2.5 * cell.dt


def test_a_movel_blend_turns_the_tool_continuously_to_the_second_orientation(cell):
    r = 0.02
    start = cell.tool(START, TCP)
    corner = start.dot(rotation_about([0.0, 0.0, 1.0], 0.3))
    corner[:3, 3] = start[:3, 3] + [0.1, 0.0, 0.0]
    end = corner.dot(rotation_about([1.0, 0.0, 0.0], 0.3))
    end[:3, 3] = corner[:3, 3] + [0.0, 0.1, 0.0]
    first = tm.LinearMove(cell.arm, TCP, START, None, corner, r=r)
    joints, poses, switch, second = blended_run(
        cell, first, lambda m: tm.LinearMove(cell.arm, TCP, None, None, end, previous=m), START, TCP)
    assert math.degrees(angle_between(poses[-1][:3, :3], end[:3, :3])) < 0.1
    rates = np.array([angle_between(p[:3, :3], n[:3, :3]) / cell.dt for p, n in zip(poses, poses[1:])])
    # Each move turns 0.3 rad over 0.1 m: 3 rad/s per m/s of the tool, and the blend's two turns share v.
    assert np.max(rates) <= 3.0 * tm.MOVEL_V * 1.02
    assert np.max(np.abs(np.diff(rates))) <= 2.0 * 3.0 * tm.MOVEL_A * cell.dt + 1e-3


def test_two_movep_at_an_oblique_corner_into_a_faster_move_keep_the_tool_speed_continuous(cell):
    # A 60 degree turn (an arc's radius is cut / tan(turn / 2); only at 90 degrees is that cut itself), into
    # a move twice as fast: the arc starts at the speed the tool has, then speeds up at a.
    r = 0.03
    start = cell.tool(START, TCP)
    corner, end = start.copy(), start.copy()
    corner[:3, 3] += [0.12, 0.0, 0.0]
    end[:3, 3] = corner[:3, 3] + 0.1 * np.array([math.cos(math.radians(60)), 0.0, -math.sin(math.radians(60))])
    first = tm.ProcessMove(cell.arm, TCP, START, None, corner, v=0.1, r=r)
    joints, poses, switch, second = blended_run(
        cell, first, lambda m: tm.ProcessMove(cell.arm, TCP, None, None, end, v=0.2, previous=m), START, TCP)
    assert second.arc is not None
    points = positions(poses)
    off_lines = off_the_lines(points, start, corner, end, 1e-3)
    assert off_lines.any()
    assert np.all(np.linalg.norm(points[off_lines] - corner[:3, 3], axis=1) <= r + 1e-4)
    velocity = speeds(cell, poses)
    assert np.max(np.linalg.norm(velocity, axis=1)) <= 0.2 * 1.02
    # The arc's centripetal acceleration (v^2 / radius, under a here) plus the tangential a.
    assert np.max(np.linalg.norm(np.diff(velocity, axis=0), axis=1)) <= 2.0 * tm.MOVEP_A * cell.dt + 1e-3
    assert np.linalg.norm(points[-1] - end[:3, 3]) < 5e-4


def test_a_movep_blend_into_a_line_too_short_to_stop_in_at_a_stops_on_target_without_speeding_up(cell):
    # Turning back by 150 degrees into 22 mm: the arc and that line are shorter than the tool needs to stop
    # from the speed it enters r with (decelerating at a since 56 mm before the corner: v0^2 / 2a = cut),
    # so it stops harder than a.
    a, v, r = 0.2, 0.15, 0.02
    start = cell.tool(START, TCP)
    corner, end = start.copy(), start.copy()
    corner[:3, 3] += [0.12, 0.0, 0.0]
    end[:3, 3] = corner[:3, 3] + 0.022 * np.array([math.cos(math.radians(150)), math.sin(math.radians(150)), 0.0])
    first = tm.ProcessMove(cell.arm, TCP, START, None, corner, a=a, v=v, r=r)
    joints, poses, switch, second = blended_run(
        cell, first, lambda m: tm.ProcessMove(cell.arm, TCP, None, None, end, a=a, v=v, previous=m), START, TCP)
    assert second.arc is not None
    points = positions(poses)
    entering = float(np.linalg.norm(speeds(cell, poses)[switch - 1]))
    assert second.path_length < entering ** 2 / (2.0 * a)
    assert np.max(np.linalg.norm(speeds(cell, poses), axis=1)) <= v * 1.02
    assert np.max(np.linalg.norm(speeds(cell, poses[switch:]), axis=1)) <= entering * 1.02
    assert np.linalg.norm(points[-1] - end[:3, 3]) < 5e-4
    assert second.done


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


def test_speedl_and_stopl_ramp_the_rotation_at_aRot(cell):
    # Linear 0.05 m/s at a = 0.5 takes 0.1 s, angular 0.4 rad/s at aRot = 0.8 takes 0.5 s: both arrive
    # together, at the later; stopl's aRot = 2.0 makes the rotation's 0.2 s the later there.
    xd = np.array([0.05, 0.0, 0.0, 0.0, 0.0, 0.4])
    motion = tm.ToolSpeed(cell.arm, TCP, START, None, xd, 0.5, aRot=0.8)
    joints, poses = run(cell, motion, START, until='returned', tcp=TCP)
    assert abs((len(poses) - 1) * cell.dt - 0.5) <= 1.5 * cell.dt
    stop = tm.ToolStop(cell.arm, TCP, None, None, 0.5, aRot=2.0, previous=motion)
    stop_joints, stop_poses = run(cell, stop, joints[-1], tcp=TCP)
    assert abs((len(stop_poses) - 1) * cell.dt - 0.2) <= 1.5 * cell.dt
    # Decelerating uniformly from 0.4 rad/s over 0.2 s: 0.04 rad.
    assert abs(angle_between(stop_poses[0][:3, :3], stop_poses[-1][:3, :3]) - 0.04) < 0.02 * 0.04 + 1e-4


def test_speedl_beyond_the_joints_speed_limits_with_a_turn_scales_both_parts_alike(cell):
    xd = np.array([0.0, 0.0, -3.0, 0.0, 0.0, 1.0])
    motion = tm.ToolSpeed(cell.arm, None, START, None, xd, 20.0)
    joints, poses = [START], [cell.tool(START)]
    for _ in range(int(0.2 / cell.dt)):
        joints.append(motion.step(cell.dt, joints[-1], None))
        poses.append(cell.tool(joints[-1]))
    assert np.all(np.abs(np.diff(np.array(joints), axis=0)) / cell.dt <= cell.arm.velocity * (1.0 + 1e-3))
    linear = speeds(cell, poses)[-1][2]
    turn = pose_from_ur_pose([0, 0, 0] + list(tm.ur_pose_of(poses[-1].dot(np.linalg.inv(poses[-2])))[3:]))
    angular = tm.ur_pose_of(turn)[5] / cell.dt
    assert linear < -0.1 and abs(angular / linear - xd[5] / xd[2]) < 0.02 * abs(xd[5] / xd[2])


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


def test_speedj_ramps_the_joints_together_at_the_leading_joints_a(cell):
    qd = np.array([0.2, -0.1, 0.0, 0.0, 0.0, 0.3])
    motion = tm.JointSpeed(cell.arm, START, None, qd, 1.0)
    joints, _ = run(cell, motion, START, until='returned')
    assert abs((len(joints) - 1) * cell.dt - 0.3 / 1.0) <= 1.5 * cell.dt  # the leading joint: 0.3 rad/s at 1
    # Every cycle's joint speeds in proportion to qd: all joints reach their speeds together.
    for speed in np.diff(np.array(joints), axis=0) / cell.dt:
        assert np.allclose(speed, qd * (speed[5] / qd[5]), atol=1e-9)


def test_speedj_beyond_the_joints_speed_limits_is_scaled_down_in_the_same_direction(cell):
    qd = np.array([6.0, 0.0, 0.0, 0.0, 0.0, -9.0])
    motion = tm.JointSpeed(cell.arm, START, None, qd, 40.0, t=0.4)
    joints, _ = run(cell, motion, START, until='returned')
    joint_speeds = np.diff(np.array(joints), axis=0) / cell.dt
    assert np.all(np.abs(joint_speeds) <= cell.arm.velocity * (1.0 + 1e-9))
    last = joint_speeds[-1]
    assert np.isclose(np.max(np.abs(last) / cell.arm.velocity), 1.0)  # as fast as the tightest joint goes
    assert np.allclose(last, qd * (last[0] / qd[0]), atol=1e-9)


def test_servoj_follows_with_the_lookahead_time_given(cell):
    target = START + 0.05
    q, motion = START, None
    steps = int(round(0.1 / cell.dt))
    for _ in range(steps):
        motion = tm.Servo(cell.arm, q, None, target, t=cell.dt, lookahead_time=0.04, previous=motion)
        q = motion.step(cell.dt, q, None)
    assert np.allclose(q - START, 0.05 * (1.0 - math.exp(-steps * cell.dt / 0.04)), rtol=1e-6)


def test_servoj_returns_after_its_t(cell):
    motion = tm.Servo(cell.arm, START, None, START + 0.05, t=0.05)
    joints, _ = run(cell, motion, START, until='returned')
    assert abs((len(joints) - 1) * cell.dt - 0.05) <= 1.5 * cell.dt
    assert motion.done


def test_servoj_beyond_the_joint_limits_is_refused_with_one_line(cell):
    target = START.copy()
    target[2] = cell.arm.upper[2] + 0.2
    with pytest.raises(tm.MotionError) as error:
        tm.Servo(cell.arm, START, None, target)
    assert '\n' not in str(error.value) and 'limit' in str(error.value)


def test_servoj_to_a_far_target_stays_within_the_joints_speed_limits(cell):
    target = START + np.array([1.0, -0.8, 0.8, 1.0, -1.0, 1.0])
    motion = tm.Servo(cell.arm, START, None, target, t=0.2)
    joints, _ = run(cell, motion, START)
    joint_speeds = np.abs(np.diff(np.array(joints), axis=0)) / cell.dt
    assert np.all(joint_speeds <= cell.arm.velocity * (1.0 + 1e-9))
    assert np.isclose(np.max(joint_speeds[0] / cell.arm.velocity), 1.0)  # the lag asks for more at first


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


def test_movej_with_t_shorter_than_its_profile_takes_t_within_the_joints_speed_limits(cell):
    # 0.3 rad at the default a: a triangle of 2 sqrt(d / a) = 0.93 s, peak sqrt(d a). Squeezed into 0.5 s it
    # takes 0.5 s; into 0.05 s it would need 12 rad/s: the joint's limit wins, and no triangle under it
    # covers 0.3 rad in less than 2 d / limit.
    target = START + np.array([0.3, 0.0, 0.0, 0.0, 0.0, 0.0])
    motion = tm.JointMove(cell.arm, START, None, target, t=0.5)
    joints, _ = run(cell, motion, START)
    assert abs((len(joints) - 1) * cell.dt - 0.5) <= 1.5 * cell.dt
    motion = tm.JointMove(cell.arm, START, None, target, t=0.05)
    joints, _ = run(cell, motion, START)
    limit = cell.arm.velocity[0]
    assert abs((len(joints) - 1) * cell.dt - 2.0 * 0.3 / limit) <= 1.5 * cell.dt
    assert np.max(np.abs(np.diff(np.array(joints), axis=0)) / cell.dt) <= limit * (1.0 + 1e-9)
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
