"""Programs as PolyScope and the drivers write them, run on the simulated arm's core (core.ArmCore).

The programs are test/data/urscript/real/*.script: PolyScope exports (the
installation header PolyScope writes first, program labels `$ n "text"`) for
each generation, a driver-style servo stream whose threads share their
command inside critical sections, and a program that follows a driver's
reverse interface as ur_robot_driver's External Control program does. Each test states what the robot must hold
after the program: outputs, payload, TCP, the joints, the log.
"""
import math
import os
import socket
import struct

import numpy as np
import pytest
import rospkg

from ur3_ft_gripper_testing.model import PACKAGE_DIR

from ur3_ft_gripper_description import urscript
from ur3_ft_gripper_description.urscript import functions as urscript_functions
from ur3_ft_gripper_description.devices.ur_arm import core as arm_core
from ur3_ft_gripper_description.devices.ur_arm import joints as jm
from ur3_ft_gripper_description.devices.ur_arm import robot_state as rs
from ur3_ft_gripper_description.devices.ur_arm import script_robot
from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings

PROGRAMS = os.path.join(PACKAGE_DIR, 'test', 'data', 'urscript', 'real')
# The controllers' time steps: CB3 125 Hz, e-Series 500 Hz.
STEP_TIME = {'ur3': 0.008, 'ur5e': 0.002}
HOME = [0.3, -1.4, 1.6, -1.8, -1.57, 0.2]  # the exports' Home waypoint
# The installation header's setters PolyScope writes (5.x and 3.x programs).
HEADER = ['set_gravity', 'set_tool_voltage', 'set_safety_mode_transition_hardness', 'set_analog_outputdomain',
          'set_standard_analog_input_domain', 'set_tool_analog_input_domain', 'set_input_actions_to_default',
          'set_tool_communication', 'set_tool_output_mode', 'set_tool_digital_output_mode', 'set_target_payload',
          'set_payload', 'set_tcp']
E_SERIES_TOOL_FLANGE = ['set_tool_communication', 'set_tool_output_mode', 'set_tool_digital_output_mode']


def program(name):
    with open(os.path.join(PROGRAMS, name)) as f:
        return f.read()


def make_core(configured_model, ur_type):
    config = os.path.join(rospkg.RosPack().get_path('ur_robot_driver'), 'config', '%s_controllers.yaml' % ur_type)
    values = {'~ur_type': ur_type, '~controller_config_file': config,
              'robot_description': configured_model(ur_type, False, False).text,
              '~controllers': 'joint_state_controller scaled_pos_joint_traj_controller'}
    settings = read_settings(lambda name, default=None: values.get(name, default))
    return arm_core.ArmCore(settings, jm.KinematicJoints.from_settings(settings)), 1.0 / settings.loop_hz


def run(core, dt, text, seconds=20.0):
    """Sends the program as script_command does and steps until it stops; the core's messages."""
    core.script_command(text)
    cycles = 0
    while core.script_running:
        assert cycles * dt < seconds, 'still running after %g s' % seconds
        core.step(dt)
        cycles += 1
    return core.take_messages()


def logged(core, name):
    """The value after `name ` in the robot's log line that starts with it."""
    line = next(text for text in core.robot.log if text.startswith(name + ' '))
    return line[len(name) + 1:]


def errors(messages):
    return [text for level, text in messages if level == arm_core.ERROR]


@pytest.mark.parametrize('ur_type, name', [('ur5e', 'polyscope_e_series.script'), ('ur3', 'polyscope_cb3.script')])
def test_a_polyscope_export_with_its_header_and_labels_runs_to_the_robot_state_it_sets(configured_model, ur_type,
                                                                                     name):
    core, dt = make_core(configured_model, ur_type)
    messages = run(core, dt, program(name))
    assert errors(messages) == [] and core.robot.program_state == rs.STOPPED
    robot = core.robot
    assert robot.tool_voltage == 24 and robot.payload == (1.2, (0.0, 0.0, 0.06))
    assert robot.digital_out[2] and robot.digital_out[script_robot.TOOL_OFFSET]
    assert np.allclose(core.tcp[:3, 3], [0, 0, 0.15]) and np.allclose(core.tcp[:3, :3], np.eye(3))
    # The loop ran twice, and ended at Home.
    assert float(logged(core, 'picked')) == 2
    assert np.allclose(core.motion.position, HOME, atol=1e-6)
    assert float(logged(core, 'step time')) == STEP_TIME[ur_type]


def test_the_e_series_header_is_refused_on_a_cb3_naming_the_tool_flange_setter(configured_model):
    core, dt = make_core(configured_model, 'ur3')
    text = program('polyscope_e_series.script')
    line = next(n for n, source in enumerate(text.splitlines(), 1) if 'set_tool_communication' in source)
    messages = run(core, dt, text)
    assert errors(messages) == ['script_command: the robot would not compile this script: line %d: '
                                'set_tool_communication is a URScript function the simulated robot does not offer'
                                % line]
    assert core.robot.tool_voltage == 0 and list(core.robot.log) == []


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e'])
def test_every_header_setter_of_the_manual_is_served_or_refused_by_name(configured_model, ur_type):
    core, _ = make_core(configured_model, ur_type)
    served = core.script_robot.served()
    assert set(HEADER) <= urscript.MANUAL_FUNCTIONS and 'get_steptime' in served
    refused = sorted(name for name in HEADER if name not in served)
    if ur_type == 'ur3':
        assert refused == sorted(E_SERIES_TOOL_FLANGE + ['set_target_payload'])
    else:
        assert refused == ['set_target_payload']  # 5.10 on: the simulated e-Series runs 5.9
    for name in refused:
        with pytest.raises(urscript.CompileError) as caught:
            urscript.compile_script('%s()\n' % name, served)
        assert str(caught.value) == 'line 1: %s is a URScript function the simulated robot does not offer' % name


@pytest.mark.parametrize('call, error', [
    ('set_gravity([0, 9.82, 0])', "set_gravity: the simulated arm stands upright on its base; it takes gravity "
                                  "along the base's z axis only, as [0, 0, 9.82], not [0, 9.82, 0]"),
    ('set_analog_outputdomain(2, 0)', 'set_analog_outputdomain: port must be 0 or 1, not 2'),
    ('set_tool_digital_output_mode(0, 0)', 'set_tool_digital_output_mode: mode must be 1 or 2 or 3, not 0'),
    ('set_tool_communication(1, 115200, 0, 1, 1.5, 3.5)',
     'set_tool_communication: enabled must be False or True, not 1'),
    ('set_tool_communication(True, 115200, 0, 1, 0.5, 3.5)',
     'set_tool_communication: rx_idle_chars must be a number >= 1, not 0.5'),
    ('set_safety_mode_transition_hardness(True)', 'set_safety_mode_transition_hardness: type must be 0 or 1, '
                                                  'not True'),
])
def test_a_header_setting_outside_the_manuals_values_stops_the_program_naming_it(configured_model, call, error):
    core, dt = make_core(configured_model, 'ur5e')
    messages = run(core, dt, 'textmsg("before")\n%s\ntextmsg("after")\n' % call)
    assert core.robot.log[0] == 'before' and 'after' not in core.robot.log
    assert core.robot.log[-1] == 'RuntimeException: Runtime error in line 2, column 1 Error: %s' % error
    assert len(errors(messages)) == 1


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e'])
def test_a_driver_servo_stream_shares_its_command_in_critical_sections_and_follows_it(configured_model, ur_type):
    core, dt = make_core(configured_model, ur_type)
    messages = run(core, dt, program('driver_servo.script'))
    assert errors(messages) == []
    # Each target handed over was taken once by the servo thread, whose servoj waits (physical time)
    # inside its critical section let main run; the arm ends on the last target.
    assert float(logged(core, 'received')) == 3
    last = [0.3, -1.3, 1.3, -1.3, -1.3, 0.3]
    assert np.allclose(core.motion.position, last, atol=1e-4)
    assert np.allclose([float(v) for v in logged(core, 'at')[1:-1].split(',')], last, atol=1e-4)
    assert math.isclose(core.script_robot.call('get_steptime', [], {}), STEP_TIME[ur_type])


# The driver's end of the reverse, trajectory and script command interfaces, from the client library's
# ReverseInterface, TrajectoryPointInterface and ScriptCommandInterface documentation.
MULT_JOINTSTATE = 1000000  # ReverseInterface::MULT_JOINTSTATE
MULT_TIME = 1000000  # TrajectoryPointInterface::MULT_TIME
IDLE, SERVOJ, SPEEDJ, FORWARD = 0, 1, 2, 3  # comm::ControlMode
TRAJECTORY_NOOP, TRAJECTORY_RECEIVE, TRAJECTORY_CANCEL = 0, 1, -1  # the trajectory control modes
RESULT_SUCCESS, RESULT_CANCELED = 0, 1  # TrajectoryResult
MOVEJ, MOVEL, SPLINE = 0, 1, 51  # the trajectory point types
CUBIC, QUINTIC = 1, 2  # the spline types
ZERO_FTSENSOR, SET_PAYLOAD, SET_TOOL_VOLTAGE, START_FORCE_MODE, END_FORCE_MODE = 0, 1, 2, 3, 4  # ScriptCommand
RECEIVE_TIMEOUT_MS = 20  # the driver's default robot receive timeout (RobotReceiveTimeout::millisec)
TRAJECTORY_TIMEOUT_MS = 200  # its default while forwarding a trajectory


class Listener(object):
    """One connection a program opens to the driver, on loopback, accepted and read without waiting."""

    def __init__(self):
        self.listener = socket.socket()
        self.listener.bind(('127.0.0.1', 0))
        self.listener.listen(1)
        self.listener.setblocking(False)
        self.port = self.listener.getsockname()[1]
        self.connection = None
        self.received = b''

    def connected(self):
        if self.connection is None:
            try:
                self.connection, _ = self.listener.accept()
                self.connection.setblocking(False)
            except BlockingIOError:
                pass
        return self.connection is not None

    def take_ints(self):
        """The int32 the program has sent since the last look."""
        try:
            self.received += self.connection.recv(4096)
        except BlockingIOError:
            pass
        count = len(self.received) // 4
        values, self.received = struct.unpack('>%di' % count, self.received[:4 * count]), self.received[4 * count:]
        return list(values)

    def close(self):
        for sock in (self.connection, self.listener):
            if sock is not None:
                sock.close()


class Driver(object):
    """A driver's reverse, trajectory and script command interfaces. Served from the test's own loop, a message per
    control cycle, so that the cell's clock, not the wall's, paces it."""

    def __init__(self):
        self.reverse, self.trajectory, self.script_command = Listener(), Listener(), Listener()
        self.results = []

    def connected(self):
        return all([self.reverse.connected(), self.trajectory.connected(), self.script_command.connected()])

    def write_point(self, kind, target, duration, velocity=1.05, acceleration=1.4, radius=0.0):
        """writeTrajectoryPoint(): velocity and acceleration (movej's defaults here) yield to a duration."""
        fields = [int(round(v * MULT_JOINTSTATE)) for v in target] + [0] * 6 + \
            [int(round(velocity * MULT_JOINTSTATE)), int(round(acceleration * MULT_JOINTSTATE))] + [0] * 4 + \
            [int(round(duration * MULT_TIME)), int(round(radius * MULT_TIME)), kind]
        self.trajectory.connection.sendall(struct.pack('>21i', *fields))

    def write_spline_point(self, kind, target, velocities, accelerations, duration):
        """writeTrajectorySplinePoint(): joints, velocities, accelerations (quintic), duration, spline type."""
        fields = [int(round(v * MULT_JOINTSTATE)) for v in list(target) + list(velocities) + list(accelerations)]
        self.trajectory.connection.sendall(struct.pack('>21i', *(fields + [int(round(duration * MULT_TIME)), kind,
                                                                           SPLINE])))

    def send_script_command(self, command, values=()):
        """A ScriptCommandInterface command: 28 int32, its values times MULT_JOINTSTATE."""
        fields = [command] + [int(round(v * MULT_JOINTSTATE)) for v in values]
        self.script_command.connection.sendall(struct.pack('>28i', *(fields + [0] * (28 - len(fields)))))

    def close(self):
        for listener in (self.reverse, self.trajectory, self.script_command):
            listener.close()


def motion(values, mode, timeout_ms=RECEIVE_TIMEOUT_MS):
    """A reverse message of a motion mode (write()): six values times MULT_JOINTSTATE."""
    return struct.pack('>8i', timeout_ms, *[int(round(v * MULT_JOINTSTATE)) for v in values], mode)


def trajectory_control(action, points=0, timeout_ms=TRAJECTORY_TIMEOUT_MS):
    """A reverse message in FORWARD mode (writeTrajectoryControlMessage()): the action and the point count
    as they are, not scaled."""
    return struct.pack('>8i', timeout_ms, action, points, 0, 0, 0, 0, FORWARD)


def driver_filled(text, driver):
    """The program with its placeholders filled as ur_robot_driver fills its own (UrDriver): the servers'
    address and ports, MULT_JOINTSTATE, MULT_TIME, and servoj's lookahead time and gain at the driver's
    defaults."""
    for key, value in {'SERVER_IP_REPLACE': '127.0.0.1', 'SERVER_PORT_REPLACE': str(driver.reverse.port),
                       'TRAJECTORY_SERVER_PORT_REPLACE': str(driver.trajectory.port),
                       'SCRIPT_COMMAND_SERVER_PORT_REPLACE': str(driver.script_command.port),
                       'JOINT_STATE_REPLACE': str(MULT_JOINTSTATE), 'TIME_REPLACE': str(MULT_TIME),
                       'SERVO_J_REPLACE': 'lookahead_time=0.03, gain=2000'}.items():
        text = text.replace('{{%s}}' % key, value)
    return text


def follow_driver(core, dt, message_at, seconds=10.0):
    """Runs reverse_interface.script against a Driver whose reverse message each cycle, `message_at(t, driver)`
    (t: s since the program connected), is motion(...) or trajectory_control(...), or None once the driver
    has gone away; it may write trajectory points too. The (t, joint positions) of each cycle after the connection,
    the times of the reverse messages sent, the trajectory results as (t, result), and the core's messages."""
    driver = Driver()
    core.script_command(driver_filled(program('reverse_interface.script'), driver))
    states, connected_at, sent, t = [], None, [], 0.0
    try:
        while core.script_running:
            assert t < seconds, 'still running after %g s; the log ends %s, the messages %s' % (
                seconds, list(core.robot.log)[-3:], core.take_messages()[-3:])
            if connected_at is None and driver.connected():
                connected_at = t
            if connected_at is not None:
                message = message_at(t - connected_at, driver)
                if message is not None:
                    driver.reverse.connection.sendall(message)
                    sent.append(t - connected_at)
            core.step(dt)
            t += dt
            if connected_at is not None:
                states.append((t - connected_at, core.actual_state()[0]))
                driver.results += [(t - connected_at, value) for value in driver.trajectory.take_ints()]
    finally:
        driver.close()
    return states, sent, driver.results, core.take_messages()


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e'])
def test_a_reverse_interface_program_follows_servoj_targets_and_stops_when_the_keepalive_stops(
        configured_model, ur_type):
    core, dt = make_core(configured_model, ur_type)
    start = core.actual_state()[0]
    speed = np.array([0.2, 0.0, -0.1, 0.0, 0.0, 0.3])  # rad/s for one second, then held for half a second

    def target(t):
        return start + speed * min(t, 1.0)

    states, sent, _, messages = follow_driver(
        core, dt, lambda t, driver: motion(target(t), SERVOJ) if t < 1.5 else None)
    assert errors(messages) == []
    # Following: behind the ramp by about servoj's lookahead time (0.03 s), never by more than 0.05 s of it.
    ramp = [(t, q) for t, q in states if 0.1 < t < 1.0]
    lag = max(np.max(np.abs(target(t) - q)) for t, q in ramp)
    assert 0.03 * 0.3 * 0.5 < lag < 0.05 * 0.3, lag
    # Holding the last target within servo error, then stopping where it stood once the driver went quiet:
    # the program ends after one receive timeout, as the robot's does.
    assert np.allclose(states[-1][1], target(1.0), atol=1e-4)
    # The read gives up on the first cycle past the timeout; the program then ends its follower, closes the
    # socket and logs within three cycles.
    timeout = RECEIVE_TIMEOUT_MS / 1000.0
    assert timeout <= states[-1][0] - sent[-1] <= math.ceil(timeout / dt - 1e-9) * dt + 3 * dt + 1e-9
    assert list(core.robot.log)[-2:] == ['reverse_socket: nothing within 0.02',
                                         'commands followed %d' % len(sent)]
    assert np.allclose(core.actual_state()[1], 0.0)


def test_a_reverse_interface_program_runs_speedj_then_stops_in_idle(configured_model):
    core, dt = make_core(configured_model, 'ur5e')
    start = core.actual_state()[0]
    velocity = [0.1, 0.0, 0.0, 0.0, 0.0, -0.2]
    states, _, _, messages = follow_driver(
        core, dt, lambda t, driver: motion(velocity, SPEEDJ) if t < 1.0 else motion(start, IDLE) if t < 1.3 else None)
    assert errors(messages) == []
    # At the speeds asked while the driver asked for them (speedj reaches them at 40 rad/s^2 within 5 ms);
    # for a second of them, give or take the cycles a message takes to reach the follower; then at rest.
    (t0, q0), (t1, q1) = [next((t, q) for t, q in states if t >= mark) for mark in (0.2, 0.8)]
    assert np.allclose((q1 - q0) / (t1 - t0), velocity, atol=1e-6)
    moved = states[-1][1] - start
    assert np.allclose(moved, velocity, atol=0.03 * 0.2), moved
    assert np.allclose(states[-1][1], [q for t, q in states if t >= 1.2][0], atol=1e-9)
    assert np.allclose(core.actual_state()[1], 0.0)


def forwarding(write_points, count, idle_for=0.2):
    """A driver side that forwards one trajectory: `write_points(driver)` writes its `count` points with the
    start message, keepalives follow until the robot answers, then idle for `idle_for` s, then silence."""
    def driver_side(t, driver):
        if t == 0.0:
            write_points(driver)
            return trajectory_control(TRAJECTORY_RECEIVE, count)
        if not driver.results:
            return trajectory_control(TRAJECTORY_NOOP)
        return motion([0.0] * 6, IDLE) if t < driver.results[0][0] + idle_for else None
    return driver_side


def at(states, time):
    """The joint positions of the first state at or after `time`."""
    return next(q for t, q in states if t >= time - 1e-9)


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e'])
def test_a_forwarded_trajectory_runs_each_point_in_its_time_and_reports_success(configured_model, ur_type):
    core, dt = make_core(configured_model, ur_type)
    start = core.actual_state()[0]
    points = [(start + [0.3, 0.0, 0.0, 0.0, 0.0, 0.0], 1.0), (start + [0.3, -0.2, 0.2, 0.0, 0.0, 0.0], 0.5),
              (start + [0.0, -0.2, 0.2, 0.0, 0.3, 0.0], 1.0)]
    def write_points(driver):
        for target, duration in points:
            driver.write_point(MOVEJ, target, duration)

    driver_side = forwarding(write_points, len(points))
    states, _, results, messages = follow_driver(core, dt, driver_side)
    assert errors(messages) == []
    assert [value for _, value in results] == [RESULT_SUCCESS]
    # movej with a time takes that time: each point reached that long after the one before (the first after
    # the cycle or two the start message and the point take to reach the program; the next point is read
    # in the cycle after a move ends; the last cycle of a move is within 1e-6 rad of its point).
    arrivals = [next(t for t, q in states if t > 0 and np.allclose(q, target, atol=1e-6)) for target, _ in points]
    first = next(t for t, q in states if np.max(np.abs(q - start)) > 1e-9) - dt
    assert 0.0 <= first <= 3 * dt
    for before, arrival, (_, duration) in zip([first] + arrivals, arrivals, points):
        assert duration - 2 * dt < arrival - before < duration + 2 * dt, (before, arrival, duration)
    elapsed = arrivals[-1]
    assert results[0][0] == pytest.approx(elapsed, abs=3 * dt)
    assert np.allclose(states[-1][1], points[-1][0], atol=1e-9)


def test_a_cancelled_trajectory_stops_the_arm_short_of_its_point_and_reports_cancelled(configured_model):
    core, dt = make_core(configured_model, 'ur5e')
    start = core.actual_state()[0]
    target = start + [0.4, 0.0, 0.0, 0.0, 0.0, 0.0]

    def driver_side(t, driver):
        if t == 0.0:
            driver.write_point(MOVEJ, target, 2.0)
            return trajectory_control(TRAJECTORY_RECEIVE, 1)
        if t < 1.0:
            return trajectory_control(TRAJECTORY_NOOP)
        if t < 1.0 + dt / 2:
            return trajectory_control(TRAJECTORY_CANCEL)
        return motion([0.0] * 6, IDLE) if t < 1.5 else None

    states, _, results, messages = follow_driver(core, dt, driver_side)
    assert errors(messages) == []
    assert [value for _, value in results] == [RESULT_CANCELED]
    assert results[0][0] == pytest.approx(1.0, abs=0.2)  # once stopj(4.0) has stopped the arm
    # Halfway through a two-second move (moving at about 0.3 rad/s), then at rest well short of the point.
    stopped = states[-1][1]
    assert 0.15 < stopped[0] - start[0] < 0.3, stopped[0] - start[0]
    assert np.allclose(at(states, 1.3), stopped, atol=1e-9)
    assert np.allclose(core.actual_state()[1], 0.0)


def test_a_forwarded_movel_point_takes_the_tool_straight_to_its_pose_in_its_time(configured_model):
    core, dt = make_core(configured_model, 'ur5e')

    def tool(q):
        return core.arm.forward(q).dot(core.tcp)

    begin = tool(core.actual_state()[0])
    goal = begin.copy()
    goal[:3, 3] += [0.05, 0.0, 0.05]

    states, _, results, messages = follow_driver(core, dt, forwarding(
        lambda driver: driver.write_point(MOVEL, list(urscript_functions.matrix_to_pose(goal)), 1.0), 1))
    assert errors(messages) == [] and [value for _, value in results] == [RESULT_SUCCESS]
    poses = [(t, tool(q)) for t, q in states]
    first = next(t for t, pose in poses if np.linalg.norm(pose[:3, 3] - begin[:3, 3]) > 1e-9) - dt
    arrival = next(t for t, pose in poses if np.linalg.norm(pose[:3, 3] - goal[:3, 3]) < 1e-6)
    assert 1.0 - 2 * dt < arrival - first < 1.0 + 2 * dt
    # A straight line: every tool position within 0.1 mm of the segment, the orientation kept.
    direction = (goal[:3, 3] - begin[:3, 3]) / np.linalg.norm(goal[:3, 3] - begin[:3, 3])
    for _, pose in poses:
        offset = pose[:3, 3] - begin[:3, 3]
        assert np.linalg.norm(offset - offset.dot(direction) * direction) < 1e-4
        assert np.allclose(pose[:3, :3], begin[:3, :3], atol=1e-6)
    assert np.allclose(poses[-1][1], goal, atol=1e-6)


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e'])
def test_script_commands_set_the_payload_and_the_tool_voltage_beside_a_running_motion(configured_model, ur_type):
    core, dt = make_core(configured_model, ur_type)
    start = core.actual_state()[0]
    commands = [(0.1, SET_PAYLOAD, (1.25, 0.0, 0.01, 0.08)), (0.3, SET_TOOL_VOLTAGE, (12,))] + \
        ([(0.5, ZERO_FTSENSOR, ())] if ur_type == 'ur5e' else [])  # the driver offers it on the e-Series only
    pending = list(commands)

    def driver_side(t, driver):
        while pending and t >= pending[0][0]:
            driver.send_script_command(*pending.pop(0)[1:])
        return motion(start + [0.1 * min(t, 1.0), 0, 0, 0, 0, 0], SERVOJ) if t < 1.2 else None

    states, _, _, messages = follow_driver(core, dt, driver_side)
    assert errors(messages) == []
    mass, centre = core.robot.payload
    assert mass == pytest.approx(1.25) and centre == pytest.approx((0.0, 0.01, 0.08))
    assert core.robot.tool_voltage == 12
    assert [line for line in core.robot.log if line.startswith('script command')] == \
        ['script command %d' % command for _, command, _ in commands]
    assert np.allclose(states[-1][1], start + [0.1, 0, 0, 0, 0, 0], atol=1e-4)  # the motion went on


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e'])
def test_script_commands_start_and_end_force_mode_which_moves_the_free_tool_at_its_speed_limit(configured_model,
                                                                                                ur_type):
    core, dt = make_core(configured_model, ur_type)
    start = core.actual_state()[0]
    limit = 0.05  # m/s along the base's z, the compliant axis
    # startForceMode(): the task frame (the base), selection vector, wrench, type, limits, damping, gain scaling.
    force_mode = [0.0] * 6 + [0, 0, 1, 0, 0, 0] + [0, 0, 10.0, 0, 0, 0] + [2] + [0.1, 0.1, limit, 0.17, 0.17, 0.17] + \
        [0.005, 1.0]
    pending = [(0.2, START_FORCE_MODE, force_mode), (1.2, END_FORCE_MODE, ())]

    def driver_side(t, driver):
        while pending and t >= pending[0][0]:
            driver.send_script_command(*pending.pop(0)[1:])
        return motion(start, IDLE) if t < 1.6 else None

    states, _, _, messages = follow_driver(core, dt, driver_side)
    assert errors(messages) == []
    assert [line for line in core.robot.log if line.startswith('script command')] == \
        ['script command %d' % START_FORCE_MODE, 'script command %d' % END_FORCE_MODE]

    def tool(mark):
        t, q = next((t, q) for t, q in states if t >= mark)
        return t, core.arm.forward(q)[:3, 3]

    # Nothing pushes back on the kinematic cell: along the compliant axis the tool runs at its limit (it
    # reaches it within 50 ms at 10 N on the 10 kg virtual mass), across it the tool holds.
    (t0, p0), (t1, p1) = tool(0.4), tool(1.1)
    assert np.allclose((p1 - p0) / (t1 - t0), [0.0, 0.0, limit], atol=1e-6)
    # Ended, the arm stays where force mode brought it: up by about the limit times the second it ran.
    (t2, p2), (t3, p3) = tool(1.3), tool(1.55)
    assert np.allclose(p3, p2, atol=1e-9)
    assert p2[2] - tool(0.0)[1][2] == pytest.approx(limit * 1.0, abs=limit * 0.1)


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e'])
@pytest.mark.parametrize('kind', [CUBIC, QUINTIC])
def test_a_forwarded_spline_point_is_followed_along_its_polynomial(configured_model, ur_type, kind):
    core, dt = make_core(configured_model, ur_type)
    start = core.actual_state()[0]
    stroke = np.array([0.4, 0.0, -0.2, 0.0, 0.0, 0.0])
    duration = 2.0

    states, _, results, messages = follow_driver(core, dt, forwarding(
        lambda driver: driver.write_spline_point(kind, start + stroke, [0.0] * 6, [0.0] * 6, duration), 1,
        idle_for=0.5))
    assert errors(messages) == [] and [value for _, value in results] == [RESULT_SUCCESS]
    # From rest to rest: a cubic is 3s^2 - 2s^3 of the stroke at s = t / T, a quintic (minimum jerk)
    # 10s^3 - 15s^4 + 6s^5. servoj follows behind by its lookahead and the cycles a target takes to reach
    # it: within 0.06 s of motion of the path (at most 0.3 rad/s here), where the two differ by 0.02 rad
    # at s = 1/4.
    def path(s):
        s = min(max(s, 0.0), 1.0)
        return (3 * s ** 2 - 2 * s ** 3) if kind == CUBIC else (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)

    first = next(t for t, q in states if np.max(np.abs(q - start)) > 1e-9) - dt
    for fraction in (0.25, 0.5, 0.75):
        q = at(states, first + fraction * duration)
        assert np.allclose(q, start + stroke * path(fraction), atol=0.06 * 0.3), (fraction, q - start)
    # The trajectory's end stops the arm (stopj) where servoj has brought it: behind the last target by
    # its lag at the speed of the last cycles, a fraction of a milliradian.
    assert np.allclose(states[-1][1], start + stroke, atol=1e-3)
