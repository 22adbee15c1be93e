"""URScript programs as users send them, run on the simulated arm's core (core.ArmCore), no ROS master.

The programs are test/data/urscript/arm/*.script. Each is sent to the core as
script_command sends it and stepped until the program stops, on ur3 (CB3, 8 ms
cycles) and ur5e (e-Series, 2 ms) where the arm's motion matters. Programs
report with textmsg ("name value"), read back from the robot's log. Every
expected outcome is worked out here from the manual's definitions: the tool is
measured with kinematics.Model's generic URDF chain (base -> tool0), not with the
ArmKinematics the motions use; poses are matrices by Rodrigues' formula and
roll-pitch-yaw is Rz Ry Rx, written out below; move times are the trapezoid's.
"""
import math
import os

import numpy as np
import pytest
import rospkg

from ur3_ft_gripper_testing.model import PACKAGE_DIR

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices.ur_arm import core as arm_core
from ur3_ft_gripper_description.devices.ur_arm import joints as jm
from ur3_ft_gripper_description.devices.ur_arm import robot_state as rs
from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings

PROGRAMS = os.path.join(PACKAGE_DIR, 'test', 'data', 'urscript', 'arm')
JOINTS = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
          'wrist_3_joint']
START = np.array([0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0])  # the node's default
HOME = np.array([0.3, -1.4, 1.6, -1.8, -1.57, 0.2])  # the programs' first waypoint: elbow bent, tool down
# textmsg writes numbers with 6 decimals: what a printed value can be off by.
PRINTED = 2e-6
# movej's and movel's defaults (the manual's Module motion).
MOVEJ_A, MOVEJ_V, MOVEL_A, MOVEL_V = 1.4, 1.05, 1.2, 0.25


# -- the manual's pose math, written out ------------------------------------------------------------

def skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotation(rotvec):
    """Rodrigues: the rotation of angle |rotvec| about rotvec."""
    angle = float(np.linalg.norm(rotvec))
    if angle < 1e-15:
        return np.eye(3)
    k = skew(np.asarray(rotvec, dtype=float) / angle)
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * k.dot(k)


def rotvec_of(r):
    """The rotation vector of a rotation matrix (angle in [0, pi)), the inverse of rotation()."""
    angle = math.acos(max(-1.0, min(1.0, (np.trace(r) - 1.0) / 2.0)))
    if angle < 1e-15:
        return np.zeros(3)
    axis = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]) / (2.0 * math.sin(angle))
    return axis * angle


def pose_matrix(pose):
    """p[x, y, z, rx, ry, rz] as the 4x4 transform [R p; 0 1]."""
    t = np.eye(4)
    t[:3, :3] = rotation(pose[3:6])
    t[:3, 3] = pose[:3]
    return t


def translation(x, y, z):
    return pose_matrix([x, y, z, 0.0, 0.0, 0.0])


def rpy_matrix(roll, pitch, yaw):
    """The manual's roll-pitch-yaw: about the base's x, then y, then z (R = Rz Ry Rx)."""
    return rotation([0, 0, yaw]).dot(rotation([0, pitch, 0])).dot(rotation([roll, 0, 0]))


def angle_between(r1, r2):
    # |R1 - R2| (Frobenius) is 2 sqrt(2) sin(angle / 2): unlike acos of the trace, precise near 0.
    return 2.0 * math.asin(min(1.0, np.linalg.norm(r1 - r2) / (2.0 * math.sqrt(2.0))))


def assert_pose(actual, expected, metres, radians, what='pose'):
    """Two 4x4 poses: the same point within `metres`, the same orientation within `radians`."""
    off = float(np.linalg.norm(actual[:3, 3] - expected[:3, 3]))
    turned = angle_between(actual[:3, :3], expected[:3, :3])
    assert off <= metres and turned <= radians, '%s off by %.3g m and %.3g rad' % (what, off, turned)


def trapezoid_time(distance, v, a):
    """A rest-to-rest move over `distance`: peak speed v, acceleration a (a triangle when v is not reached)."""
    return distance / v + v / a if distance >= v * v / a else 2.0 * math.sqrt(distance / a)


def distance_to_segment(points, a, b):
    direction = (b - a) / np.linalg.norm(b - a)
    along = np.clip((points - a).dot(direction), 0.0, np.linalg.norm(b - a))
    return np.linalg.norm(points - (a + along[:, None] * direction), axis=1)


def parse(text):
    """A value as textmsg writes it: a number, a bool, a pose or list (of numbers or words)."""
    if text in ('True', 'False'):
        return text == 'True'
    if text.startswith('p['):
        return [float(v) for v in text[2:-1].split(',')]
    if text.startswith('['):
        items = [item.strip() for item in text[1:-1].split(',')]
        try:
            return [float(item) for item in items]
        except ValueError:
            return items
    return float(text)


# -- the arm, running a program ----------------------------------------------------------------------

class Ran(object):
    """What a program did: the joints after each cycle (the start first), the log and the core's messages."""

    def __init__(self, joints, log_lengths, log, messages):
        self.joints = joints
        self.log_lengths = log_lengths
        self.log = log
        self.messages = messages

    @property
    def final(self):
        return self.joints[-1]

    def _line(self, name):
        for index, line in enumerate(self.log):
            if line == name or line.startswith(name + ' '):
                return index
        raise AssertionError('the program logged no %r: %s' % (name, self.log))

    def value(self, name):
        return parse(self.log[self._line(name)][len(name) + 1:])

    def cycle(self, name):
        """The cycle (1 = the first) in which the program logged `name`."""
        index = self._line(name)
        return next(k for k, length in enumerate(self.log_lengths) if length > index)

    def between(self, first, last):
        """The joints through the motion that follows line `first` up to line `last`: the cycle before
        `first` (where it starts) to the cycle before `last` (where it ended)."""
        return np.array(self.joints[self.cycle(first) - 1:self.cycle(last)])


class Arm(object):
    """The simulated arm's core as the node builds it, and an independent forward kinematics of its model."""

    def __init__(self, configured_model, ur_type):
        text = configured_model(ur_type, False, False).text
        config = os.path.join(rospkg.RosPack().get_path('ur_robot_driver'), 'config', '%s_controllers.yaml' % ur_type)
        values = {'~ur_type': ur_type, '~controller_config_file': config, 'robot_description': text,
                  '~controllers': 'joint_state_controller scaled_pos_joint_traj_controller'}
        settings = read_settings(lambda name, default=None: values.get(name, default))
        self.core = arm_core.ArmCore(settings, jm.KinematicJoints.from_settings(settings))
        self.model = kinematics.Model(text)
        self.dt = 1.0 / settings.loop_hz

    def tool(self, q, tcp=None):
        pose = self.model.transform('base', 'tool0', dict(zip(JOINTS, q)))
        return pose if tcp is None else pose.dot(tcp)

    def run(self, name, seconds=15.0):
        with open(os.path.join(PROGRAMS, name)) as f:
            text = f.read()
        core = self.core
        joints = [np.array(core.motion.position, dtype=float)]
        log_lengths = [len(core.robot.log)]
        core.script_command(text)
        while core.script_running:
            assert len(joints) * self.dt < seconds, '%s still runs after %g s' % (name, seconds)
            core.step(self.dt)
            joints.append(np.array(core.motion.position, dtype=float))
            log_lengths.append(len(core.robot.log))
        return Ran(joints, log_lengths, list(core.robot.log), core.take_messages())

    def stopped(self):
        return not self.core.script_running and self.core.robot.program_state == rs.STOPPED


@pytest.fixture(params=['ur3', 'ur5e'])
def arm(request, configured_model):
    return Arm(configured_model, request.param)


@pytest.fixture
def e_series(configured_model):
    """For programs whose outcome does not depend on the arm."""
    return Arm(configured_model, 'ur5e')


def source_line(name, text):
    """(line, column), 1-based, where `text` first appears in program `name`."""
    with open(os.path.join(PROGRAMS, name)) as f:
        for number, line in enumerate(f, 1):
            if text in line:
                return number, line.index(text) + 1
    raise AssertionError('%r is not in %s' % (text, name))


# -- motions ------------------------------------------------------------------------------------------

def test_movej_to_joint_positions_moves_straight_in_joint_space_in_the_trapezoid_time(arm):
    ran = arm.run('movej_joints.script')
    place = np.array([1.1, -1.2, 1.3, -1.7, -1.57, -0.4])
    assert np.allclose(ran.final, place, atol=1e-9)
    assert np.allclose(ran.value('home'), HOME, atol=PRINTED)
    assert np.allclose(ran.value('place'), place, atol=PRINTED)
    path = ran.between('home', 'place')
    # The leading joint (0.8 rad) at v=0.5, a=1.2; the program goes on in the cycle after the move ends.
    assert abs((len(path) - 1) * arm.dt - trapezoid_time(0.8, 0.5, 1.2)) <= arm.dt
    # All joints start and stop together: every moving joint has covered the same share of its way.
    moving = place != HOME
    shares = (path - HOME)[:, moving] / (place - HOME)[moving]
    assert np.allclose(shares, shares[:, :1], atol=1e-9)


def test_movej_to_a_pose_puts_the_tcp_on_it_by_the_nearest_joints(arm):
    ran = arm.run('movej_pose.script')
    above_part = pose_matrix([-0.28, -0.18, 0.22, 0, 3.1416, 0])
    assert_pose(arm.tool(ran.final), above_part, 1e-6, 1e-6)
    assert_pose(pose_matrix(ran.value('tcp')), above_part, PRINTED, PRINTED)
    # The solution on the branch the arm is on: shoulder, elbow and wrist bent the same way as at the start.
    assert np.all(np.sign(ran.final[1:5]) == np.sign(START[1:5]))
    moving = np.abs(ran.final - START) > 1e-6
    shares = (np.array(ran.joints) - START)[:, moving] / (ran.final - START)[moving]
    assert np.allclose(shares, shares[:, :1], atol=1e-9)  # still a joint move


def test_movel_runs_the_tool_straight_at_its_speed_to_the_target(arm):
    ran = arm.run('movel_insert.script')
    above = arm.tool(HOME)
    inserted = above.dot(translation(0, 0, 0.06))
    path = ran.between('inserting', 'inserted')
    poses = [arm.tool(q) for q in path]
    points = np.array([p[:3, 3] for p in poses])
    assert_pose(poses[0], above, 1e-9, 1e-9, 'start')
    assert_pose(poses[-1], inserted, 1e-6, 1e-6, 'inserted')
    assert np.max(distance_to_segment(points, above[:3, 3], inserted[:3, 3])) < 1e-6
    assert max(angle_between(p[:3, :3], above[:3, :3]) for p in poses) < 1e-6
    speeds = np.linalg.norm(np.diff(points, axis=0), axis=1) / arm.dt
    assert 0.1 * 0.99 <= np.max(speeds) <= 0.1 * 1.001
    assert abs((len(path) - 1) * arm.dt - trapezoid_time(0.06, 0.1, 0.5)) <= arm.dt
    assert_pose(pose_matrix(ran.value('inserted')), inserted, PRINTED, PRINTED, 'inserted, as logged')
    # The way back: shifted and turned in the tool's frame, at movel's default a and v.
    retracted = above.dot(pose_matrix([0.03, -0.02, 0, 0, 0, 0.4]))
    assert_pose(arm.tool(ran.final), retracted, 1e-6, 1e-6, 'retracted')
    assert_pose(pose_matrix(ran.value('retracted')), retracted, PRINTED, PRINTED, 'retracted, as logged')


def test_movep_keeps_the_tool_speed_through_the_blended_corners(arm):
    ran = arm.run('movep_dispense.script')
    start = arm.tool(HOME)
    corners = [start.dot(translation(0.08, 0, 0)), start.dot(translation(0.08, 0.08, 0))]
    end = start.dot(translation(0, 0.08, 0))
    path = [arm.tool(q) for q in ran.between('dispensing', 'done')]
    points = np.array([p[:3, 3] for p in path])
    assert_pose(path[-1], end, 1e-6, 1e-6, 'end')
    assert max(angle_between(p[:3, :3], start[:3, :3]) for p in path) < 1e-6
    ways = [start[:3, 3]] + [c[:3, 3] for c in corners] + [end[:3, 3]]
    on_lines = np.min([distance_to_segment(points, a, b) for a, b in zip(ways, ways[1:])], axis=0) < 1e-6
    near_corner = np.min([np.linalg.norm(points - c, axis=1) for c in ways[1:3]], axis=0)
    assert np.all(near_corner[~on_lines] <= 0.02 + 1e-6)  # off the lines only within r of a corner
    for corner in ways[1:3]:
        assert np.min(np.linalg.norm(points - corner, axis=1)) > 1e-3  # ... and it is cut
    # Constant tool speed v between the ramps at the two ends (v^2 / 2a long, a cycle's travel of slack).
    speeds = np.linalg.norm(np.diff(points, axis=0), axis=1) / arm.dt
    travelled = np.cumsum(speeds * arm.dt)
    ramp = 0.1 ** 2 / (2 * 1.2) + 0.1 * arm.dt
    cruising = (travelled > ramp) & (travelled < travelled[-1] - ramp)
    assert cruising.sum() > 0.8 * len(speeds)
    assert np.all(np.abs(speeds[cruising] - 0.1) < 0.01 * 0.1)


def test_blends_cut_the_corner_within_r_and_save_time(arm):
    ran = arm.run('blends.script')
    start = arm.tool(HOME)
    corner, end = start.dot(translation(0.1, 0, 0)), start.dot(translation(0.1, 0.1, 0))
    joints = ran.between('movel blend', 'movej blend')
    points = np.array([arm.tool(q)[:3, 3] for q in joints])
    assert np.linalg.norm(points[-1] - end[:3, 3]) < 1e-6
    on_lines = np.minimum(distance_to_segment(points, start[:3, 3], corner[:3, 3]),
                          distance_to_segment(points, corner[:3, 3], end[:3, 3])) < 1e-6
    assert (~on_lines).any()  # a blend, not a stop at the corner
    assert np.all(np.linalg.norm(points[~on_lines] - corner[:3, 3], axis=1) <= 0.03 + 1e-6)
    assert np.min(np.linalg.norm(points - corner[:3, 3], axis=1)) > 1e-3
    velocity = np.diff(points, axis=0) / arm.dt
    assert np.max(np.linalg.norm(velocity, axis=1)) <= MOVEL_V * 1.01
    # Continuous: no cycle changes the tool's velocity by more than the acceleration allows.
    assert np.max(np.linalg.norm(np.diff(velocity, axis=0), axis=1)) <= 2 * MOVEL_A * arm.dt + 1e-3
    alone = 2 * trapezoid_time(0.1, MOVEL_V, MOVEL_A)
    assert (len(joints) - 1) * arm.dt < alone - 0.5 * MOVEL_V / MOVEL_A
    # movej with r: the joints never stop at the middle waypoint; the tool passes within r of it.
    middle = np.array([0.6, -1.3, 1.5, -1.8, -1.57, 0.2])
    last = np.array([0.6, -1.5, 1.8, -1.9, -1.57, 0.5])
    joints = ran.between('movej blend', 'end')
    assert np.allclose(joints[-1], last, atol=1e-9)
    assert np.min(np.max(np.abs(joints - middle), axis=1)) > 1e-3
    tool_to_middle = np.linalg.norm([arm.tool(q)[:3, 3] - arm.tool(middle)[:3, 3] for q in joints], axis=1)
    assert np.min(tool_to_middle) <= 0.05
    joint_speeds = np.diff(joints, axis=0) / arm.dt
    assert np.max(np.abs(joint_speeds)) <= MOVEJ_V * 1.001
    alone = (trapezoid_time(np.max(np.abs(middle - joints[0])), MOVEJ_V, MOVEJ_A)
             + trapezoid_time(np.max(np.abs(last - middle)), MOVEJ_V, MOVEJ_A))
    assert (len(joints) - 1) * arm.dt < alone - arm.dt


def test_a_servoj_stream_is_followed_with_the_lookahead_lag(arm):
    ran = arm.run('servoj_stream.script')
    # The simulation's servoj (tool_motion.py; the manual gives no formula): each target is held for t
    # and followed as a first-order lag with lookahead_time as its time constant, whatever the cycle.
    t, lookahead, steps = 0.008, 0.05, 250
    q = START.copy()
    for i in range(steps):
        target = START + np.array([0.25, 0, 0, 0, 0, -0.25]) * i / steps
        q = target + (q - target) * math.exp(-t / lookahead)
    assert np.allclose(ran.final, q, atol=1e-9)
    assert ran.value('streamed') == steps
    # Each servoj returned after its t: the stream lasted steps * t.
    assert (ran.cycle('streamed') - 1) * arm.dt == pytest.approx(steps * t)


def test_speedj_then_stopj_travels_the_ramps_and_the_cruise(arm):
    ran = arm.run('speedj_stopj.script')
    qd = np.array([0.2, 0, 0, 0, 0, -0.3])
    # The leading joint's 0.3 rad/s takes 0.3 s at a=1; speedj returns after t=0.5; stopj's a=2 stops
    # it in 0.15 s; every joint on the same profile: half the ramps plus the cruise at qd.
    expected = HOME + qd * (0.3 / 2 + (0.5 - 0.3) + 0.15 / 2)
    # speedj can only return at the end of a cycle: up to one cycle at qd more.
    assert np.all(np.abs(ran.final - expected) <= np.abs(qd) * arm.dt + 1e-9), ran.final - expected
    assert np.allclose(ran.value('joints'), ran.final, atol=PRINTED)
    # At rest: at most the last cycle's mean speed, while it came to a stop.
    assert np.all(np.abs(ran.value('speeds')) <= 2.0 * arm.dt + PRINTED)


def test_speedl_then_stopl_moves_the_tool_along_xd_without_turning_it(arm):
    ran = arm.run('speedl_stopl.script')
    xd = np.array([0.05, 0, -0.04])
    start = arm.tool(HOME)
    # Up to speed at a, on, and down at the same a: the tool covers xd * t, as if at xd all along.
    expected = start.copy()
    expected[:3, 3] += xd * 0.6
    stopped = arm.tool(ran.final)
    assert np.all(np.abs(stopped[:3, 3] - expected[:3, 3]) <= np.abs(xd) * arm.dt + 1e-6), \
        stopped[:3, 3] - expected[:3, 3]
    assert angle_between(stopped[:3, :3], start[:3, :3]) < 1e-6
    assert_pose(pose_matrix(ran.value('start')), start, PRINTED, PRINTED, 'start, as logged')
    assert_pose(pose_matrix(ran.value('stopped')), stopped, PRINTED, PRINTED, 'stopped, as logged')


# -- poses, kinematics and state ---------------------------------------------------------------------

def test_the_pose_functions_give_the_manuals_matrices(e_series):
    ran = e_series.run('pose_functions.script')
    table = pose_matrix([0.3, -0.2, 0.05, 0, 0, 0.7854])
    part = pose_matrix([0.05, 0.02, 0.01, 0.2, -0.1, 0.5])
    approach = pose_matrix([0.1, 0, 0.12, 0, 1.2, 0])

    def logged(name, expected):
        assert_pose(pose_matrix(ran.value(name)), expected, PRINTED, PRINTED, name)

    logged('trans', table.dot(part))
    logged('inverse', np.linalg.inv(table))
    added, subtracted = np.eye(4), np.eye(4)
    # pose_add and pose_sub: positions added (subtracted), rotations composed in the base frame.
    added[:3, :3], added[:3, 3] = table[:3, :3].dot(part[:3, :3]), table[:3, 3] + part[:3, 3]
    subtracted[:3, :3], subtracted[:3, 3] = table[:3, :3].dot(part[:3, :3].T), table[:3, 3] - part[:3, 3]
    logged('add', added)
    logged('sub', subtracted)
    assert ran.value('shift') == pytest.approx(0.05, abs=PRINTED)  # a 3-4-5 shift
    assert ran.value('turn') == pytest.approx(0.5, abs=PRINTED)    # a pure turn has its angle as distance
    # Both at once: the distance and the angle combined as one norm (doc/urscript.md's choice).
    combined = math.hypot(np.linalg.norm(part[:3, 3] - table[:3, 3]), angle_between(table[:3, :3], part[:3, :3]))
    assert ran.value('dist') == pytest.approx(combined, abs=PRINTED)

    def interpolated(a, b, alpha):
        pose = np.eye(4)
        pose[:3, 3] = a[:3, 3] + alpha * (b[:3, 3] - a[:3, 3])
        pose[:3, :3] = a[:3, :3].dot(rotation(alpha * rotvec_of(a[:3, :3].T.dot(b[:3, :3]))))
        return pose
    logged('halfway', interpolated(table, table.dot(approach), 0.5))
    logged('quarter', interpolated(table, part, 0.25))
    for name, rotvec in (('manual_rpy', [3.14, 1.57, 0]), ('rpy', [0.3, -1.2, 0.6])):
        roll, pitch, yaw = ran.value(name)
        assert np.allclose(rpy_matrix(roll, pitch, yaw), rotation(rotvec), atol=PRINTED * 3), name
        assert abs(pitch) <= math.pi / 2
    for name, rpy in (('manual_rotvec', [3.14, 1.57, 0]), ('small_rotvec', [0.1, 0.2, 0.3])):
        assert np.allclose(rotation(ran.value(name)), rpy_matrix(*rpy), atol=PRINTED * 3), name
    # The manual's own examples, as it prints them (5 decimals).
    assert np.allclose(ran.value('manual_rpy'), [-2.80856, -0.16202, 0.9], atol=1e-5)
    assert np.allclose(ran.value('manual_rotvec'), [2.22153, 0.00177, -2.21976], atol=1e-5)


def test_the_math_functions(e_series):
    ran = e_series.run('math_functions.script')
    expected = {
        'hypotenuse': 5.0, 'sine': 0.5, 'cosine': math.cos(1.0), 'tangent': math.tan(0.5),
        'arc_cosine': math.pi / 3, 'arc_sine': -math.pi / 2, 'arc_tangent': math.atan(2.0),
        # The manual's atan2(x, y): the arc tangent of x/y, x the numerator, in the quadrant of (y, x).
        'angle': 3 * math.pi / 4, 'degrees': -45.0,
        # norm: the Euclidean norm of a list or of all six elements of a pose; |a| of a number.
        'list_norm': 3.0, 'pose_norm': math.sqrt(0.1 ** 2 + 0.2 ** 2 + 0.2 ** 2 + 0.4 ** 2), 'float_norm': 2.5,
        'power': 1024.0, 'logarithm': 10.0, 'floor': -3.0, 'ceil': 3.0, 'unit': [0.6, 0.0, 0.8],
    }
    for name, value in expected.items():
        assert np.allclose(ran.value(name), value, atol=PRINTED, rtol=0), name
    assert len(ran.log) == len(expected)


def test_forward_and_inverse_kinematics_of_the_arms_model(arm):
    ran = arm.run('kinematics_functions.script')
    other = np.array([0.8, -1.1, 1.2, -1.6, -1.4, 0.5])
    gripper = translation(0, 0, 0.15)
    # The joints are logged to 6 decimals: the tool from them is off by a few micrometres at most.
    from_joints = 1e-5
    assert_pose(pose_matrix(ran.value('forward')), arm.tool(other), PRINTED, PRINTED, 'forward')
    assert_pose(pose_matrix(ran.value('forward_here')), arm.tool(START), PRINTED, PRINTED, 'forward_here')
    assert_pose(pose_matrix(ran.value('forward_gripper')), arm.tool(other, gripper), PRINTED, PRINTED,
                'forward_gripper')
    above_part = pose_matrix([-0.25, -0.2, 0.2, 0, 3.1416, 0])
    near = np.array([0.2, -1.6, 2.0, -2.0, -1.57, -1.3])
    inverse, inverse_gripper = np.array(ran.value('inverse')), np.array(ran.value('inverse_gripper'))
    assert_pose(arm.tool(inverse), above_part, from_joints, from_joints, 'inverse')
    assert_pose(arm.tool(inverse_gripper, gripper), above_part, from_joints, from_joints, 'inverse_gripper')
    # The solution on qnear's branch of the eight: shoulder on the same side, elbow and wrist bent alike.
    for solution in (inverse, inverse_gripper):
        assert abs(solution[0] - near[0]) < math.pi / 2
        assert np.sign(solution[2]) == np.sign(near[2]) and np.sign(solution[4]) == np.sign(near[4])
    assert np.array_equal(ran.final, START)  # nothing moved
    assert np.allclose(ran.value('joints'), START, atol=PRINTED)


def test_state_functions_and_set_tcp(arm):
    ran = arm.run('tcp_state.script')
    flange = arm.tool(HOME)
    tcp = pose_matrix([0, 0.02, 0.18, 0, 0, 0.3])
    assert np.allclose(ran.value('joints'), HOME, atol=PRINTED)
    assert_pose(pose_matrix(ran.value('flange')), flange, PRINTED, PRINTED, 'actual')
    assert_pose(pose_matrix(ran.value('target')), flange, PRINTED, PRINTED, 'target')
    assert np.allclose(ran.value('offset'), 0.0, atol=0)
    assert_pose(pose_matrix(ran.value('gripper_offset')), tcp, PRINTED, PRINTED, 'set_tcp')
    gripper = flange.dot(tcp)
    assert_pose(pose_matrix(ran.value('gripper')), gripper, PRINTED, PRINTED, 'the TCP after set_tcp')
    # A movel that only turns the tool turns it about the TCP: the TCP stays, the flange swings.
    turning = ran.between('turning', 'turned')
    assert max(np.linalg.norm(arm.tool(q, tcp)[:3, 3] - gripper[:3, 3]) for q in turning) < 1e-6
    assert max(np.linalg.norm(arm.tool(q)[:3, 3] - flange[:3, 3]) for q in turning) > 0.01
    turned = gripper.dot(pose_matrix([0, 0, 0, 0, 0.3, 0]))
    assert_pose(arm.tool(ran.final, tcp), turned, 1e-6, 1e-6, 'turned')
    assert_pose(pose_matrix(ran.value('turned')), turned, PRINTED, PRINTED, 'turned, as logged')


# -- control flow, threads, halt ------------------------------------------------------------------------

def test_the_control_flow_forms(e_series):
    ran = e_series.run('control_flow.script')
    total, i = 0, 0
    while i < 20:
        i += 1
        if i % 3 == 0:
            continue
        if i > 14:
            break
        total += i

    def classify(n):
        return 'negative' if n < 0 else 'zero' if n == 0 else 'even' if n % 2 == 0 else 'odd'
    assert ran.value('total') == total and ran.value('stopped_at') == i
    assert ran.value('classes') == [classify(n) for n in (-3, 0, 4, 7)]
    assert ran.value('calls') == 4  # classify wrote the program's (global) calls
    assert ran.value('factorial') == math.factorial(10)
    assert ran.value('square') == next(k for k in range(1, 100) if k * k > 50)
    # masked_limit's `local limit` hides the program's limit, which stays 7.
    assert ran.value('masked') == 101 and ran.value('limit') == 7
    assert e_series.stopped() and not [m for m in ran.messages if m[0] == arm_core.ERROR]


def test_palletizing_loop_places_each_slot_and_skips_the_broken_one(arm):
    ran = arm.run('palletize.script')
    corner = arm.tool(HOME)
    placed, log, slot = 0, [], -1
    while True:
        slot += 1
        if slot == 4:
            log.append('skipped %d' % slot)
            continue
        elif placed >= 5:
            break
        placed += 1
        log.append('placed %d' % slot)
    assert ran.log == log + ['parts %d' % placed]
    for line in log:
        if line.startswith('placed'):
            row, column = divmod(int(line.split()[1]), 3)
            at = arm.tool(ran.joints[ran.cycle(line) - 1])
            assert_pose(at, corner.dot(translation(0.04 * column, 0.05 * row, 0)), 1e-6, 1e-6, line)


def test_threads_run_join_and_kill_beside_a_move(arm):
    ran = arm.run('threads.script')
    target = np.array([0.5, -1.3, 1.4, -1.7, -1.57, 0.3])
    move_cycles = int(math.ceil(trapezoid_time(np.max(np.abs(target - START)), MOVEJ_V, MOVEJ_A) / arm.dt - 1e-9))
    assert ran.value('moved') is True
    # The counter counted each cycle of the move, and the one or two in which join returned.
    assert move_cycles <= ran.value('cycles') <= move_cycles + 2
    assert ran.value('after_kill') == ran.value('cycles')  # killed: it counted no more
    assert np.allclose(ran.final, target, atol=1e-9)


def test_halt_stops_the_program_where_it_stands(arm):
    ran = arm.run('halt_on_reject.script')
    assert ran.log == ['rejected 2']  # halt: neither the later moves nor "all placed"
    assert np.allclose(ran.final, [0.4, -1.4, 1.6, -1.8, -1.57, 0.2], atol=1e-9)  # where code 2 put it
    assert arm.stopped() and not [m for m in ran.messages if m[0] == arm_core.ERROR]


# -- programs the robot refuses, and runtime errors ------------------------------------------------

@pytest.mark.parametrize('name, where, error', [
    ('undefined_name.script', 'get_actual_tcp_pos(', "name 'get_actual_tcp_pos' is not defined"),
    ('missing_colon.script', 'while n < 3', 'unexpected end of line'),
])
def test_a_program_that_does_not_compile_is_refused_naming_its_line(e_series, name, where, error):
    ran = e_series.run(name)
    line, _ = source_line(name, where)
    level, text = ran.messages[-1]
    assert level == arm_core.ERROR and text.endswith('would not compile this script: line %d: %s' % (line, error))
    # Refused whole: not even the lines before it ran, and External Control goes on.
    assert ran.log == [] and len(ran.joints) == 1
    assert e_series.core.robot.program_running and not e_series.core.script_running
    for _ in range(50):
        e_series.core.step(e_series.dt)
    assert np.allclose(e_series.core.motion.position, START, atol=1e-12)


def test_an_index_out_of_range_stops_the_program_after_the_moves_it_made(arm):
    ran = arm.run('index_out_of_range.script')
    line, column = source_line('index_out_of_range.script', 'path[i]')
    assert ran.log == ['reached 0', 'reached 1', 'reached 2',
                       'RuntimeException: Runtime error in line %d, column %d Error: Index out of bounds: '
                       'index 3, length 3' % (line, column)]
    assert ran.messages[-1] == (arm_core.ERROR, 'script_command: %s; program stopped' % ran.log[-1])
    assert arm.stopped()
    last_waypoint = [0.7, -1.3, 1.5, -1.7, -1.57, 0.3]
    assert np.allclose(ran.final, last_waypoint, atol=1e-9)
    for _ in range(50):
        arm.core.step(arm.dt)
    assert np.allclose(arm.core.motion.position, last_waypoint, atol=1e-9)  # stopped there


@pytest.mark.parametrize('name, call', [('unreachable_movel.script', 'movel'), ('unreachable_movej.script', 'movej')])
def test_an_unreachable_pose_stops_the_program_before_the_arm_moves(arm, name, call):
    ran = arm.run(name)
    line, column = source_line(name, call + '(p[5')
    assert ran.log[0] == 'moving' and len(ran.log) == 2  # not "arrived"
    error = ran.log[1]
    assert error.startswith('RuntimeException: Runtime error in line %d, column %d Error: %s: ' % (line, column, call))
    assert 'reach' in error and ran.messages[-1] == (arm_core.ERROR, 'script_command: %s; program stopped' % error)
    assert arm.stopped()
    assert all(np.array_equal(q, START) for q in ran.joints)
