"""The simulated UR controller's core (core.ArmCore) driven without ROS: what the node used to decide.

Each test builds the core as the node does (settings.read_settings over
ur_robot_driver's controller file and the expanded model, the kinematic
joints) and talks to it through the calls the node makes for its services,
actions and topics; time passes by step(dt).
"""
import math
import os

import numpy as np
import pytest
import yaml
from transforms3d.quaternions import mat2quat

from ur3_ft_gripper_description.devices import sim_clock, sim_params
from ur3_ft_gripper_description.devices.ur_arm import core as arm_core
from ur3_ft_gripper_description.model.names import shared_rospack
from ur3_ft_gripper_description.devices.ur_arm import controller_manager as cm
from ur3_ft_gripper_description.devices.ur_arm import joints as jm
from ur3_ft_gripper_description.devices.ur_arm import robot_state as rs
from ur3_ft_gripper_description.devices.ur_arm import software
from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import rotation_vector
from ur3_ft_gripper_description.devices.ur_arm.cartesian import Waypoint
from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings
from ur3_ft_gripper_description.devices.ur_arm.trajectory import JointTolerance, Point
from ur3_ft_gripper_description.model import description
from ur3_ft_gripper_description.number_text import number, number_list

JOINTS = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
          'wrist_3_joint']
START = [0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0]  # the node's default start pose
HOME = [0.0, -1.57, 1.57, -1.57, -1.57, 0.0]
AWAY = [0.4, -1.3, 1.2, -1.2, -1.2, 0.6]
STARTED = ['joint_state_controller', 'scaled_pos_joint_traj_controller', 'speed_scaling_state_controller',
           'force_torque_sensor_controller']
DT = 0.002
# Universal Robots' CB3 controllers are the UR3, UR5 and UR10 (the "e" models and the later
# heavy-payload ones run the e-Series software); their control loops: CB3 125 Hz, e-Series 500 Hz.
CB3_MODELS = ('ur3', 'ur5', 'ur10')
CONTROL_HZ = {'CB3': 125, 'e-Series': 500}


def driver_config(ur_type):
    return os.path.join(shared_rospack().get_path('ur_robot_driver'), 'config', '%s_controllers.yaml' % ur_type)


def make_settings(configured_model, ur_type='ur5e', **params):
    values = {'~ur_type': ur_type, '~controller_config_file': driver_config(ur_type),
              '~controllers': ' '.join(STARTED), 'robot_description': configured_model(ur_type, False, False).text}
    values.update(params)
    return read_settings(lambda name, default=None: values.get(name, default))


def make_core(configured_model, ur_type='ur5e', motion=None, **params):
    settings = make_settings(configured_model, ur_type, **params)
    return arm_core.ArmCore(settings, motion(settings) if motion else jm.KinematicJoints.from_settings(settings))


@pytest.fixture
def arm(configured_model):
    return make_core(configured_model)


def run(core, seconds, dt=DT):
    snapshot = None
    for _ in range(int(round(seconds / dt))):
        snapshot = core.step(dt)
    return snapshot


def run_until(core, condition, seconds, dt=DT):
    """Step until condition() holds; the time it took (s). Fails after `seconds`."""
    for i in range(int(round(seconds / dt))):
        core.step(dt)
        if condition():
            return (i + 1) * dt
    raise AssertionError('not within %g s' % seconds)


def finished(core):
    return [(f.controller, f.goal_id, f.outcome.status, f.outcome.code) for f in core.take_finished()]


def only(core, controller):
    ok, message = core.switch_controllers([controller], [c.name for c in core.manager.running_commanding()
                                                         if c.name != controller], cm.BEST_EFFORT)
    assert ok, message


def tool_pose(core):
    return core.arm.forward(core.motion.position)


def tcp_pose(core):
    return tool_pose(core).dot(core.tcp)


# -- the model table: every model both packages know -------------------------------------------

def both_know():
    config = os.path.join(shared_rospack().get_path('ur_robot_driver'), 'config')
    driver = {name[:-len('_controllers.yaml')] for name in os.listdir(config) if name.endswith('_controllers.yaml')}
    return sorted(driver & set(description.ur_types()))


def test_the_software_table_covers_every_model_both_packages_know():
    assert sorted(software.read_table()) == both_know()


@pytest.mark.parametrize('ur_type', sorted(software.read_table()))
def test_each_model_reports_its_generation(configured_model, ur_type):
    settings = make_settings(configured_model, ur_type)
    generation = 'CB3' if ur_type in CB3_MODELS else 'e-Series'
    core = arm_core.ArmCore(settings, jm.KinematicJoints.from_settings(settings))
    version = core.software_version()
    assert len(version) == 4 and (version[0] < 5) == (generation == 'CB3'), version
    # The loop rate is the controllers file's, which is the generation's control frequency.
    with open(driver_config(ur_type)) as f:
        assert settings.loop_hz == yaml.safe_load(f)['hardware_control_loop']['loop_hz'] == CONTROL_HZ[generation]
    ok, message = core.zero_ftsensor()
    assert ok == (generation == 'e-Series'), message
    if not ok:
        assert 'only available for e-Series robots' in message and '%d.%d.%d' % version[:3] in message
    remote = core.dashboard('is in remote control')
    assert (remote == 'true') == (generation == 'e-Series'), remote
    assert core.dashboard('PolyScopeVersion') == 'URSoftware %d.%d.%d.%d' % version


def test_ur20_and_ur30_run_e_series_software():
    for ur_type in ('ur20', 'ur30'):
        model = software.for_model(ur_type)
        assert model.e_series and model.version[0] == 5 and model.zero_ftsensor_refusal() is None


def test_an_unknown_model_is_one_line_naming_the_known_ones(configured_model):
    with pytest.raises(sim_params.ParamError) as caught:
        make_settings(configured_model, 'ur5e', **{'~ur_type': 'ur7e'})
    message = str(caught.value)
    assert '\n' not in message and "'ur7e'" in message and 'ur3, ur3e' in message and 'ur30' in message, message


# -- the joints ------------------------------------------------------------------------------

def test_kinematic_joints_follow_each_mode_within_their_limits():
    joints = jm.KinematicJoints([0.0] * 6, [-1.0] * 6, [1.0] * 6, [0.5] * 6, 0.03)
    joints.step(jm.JointCommand(jm.SERVO, [0.01] + [0.0] * 5), 0.002)
    lagged = 0.01 * (1.0 - math.exp(-0.002 / 0.03))  # servoj's first-order lag
    assert joints.position[0] == pytest.approx(lagged)
    joints.step(jm.JointCommand(jm.HOLD, [0.5] * 6), 0.002)
    assert joints.position[0] == pytest.approx(lagged) and not joints.velocity.any()
    joints.step(jm.JointCommand(jm.MOVE, [0.001] * 6), 0.002)
    assert np.allclose(joints.position, 0.001)  # the robot's own interpolation: exact
    joints.step(jm.JointCommand(jm.VELOCITY, velocity=[0.1] * 6), 0.01)
    assert np.allclose(joints.position, 0.002) and np.allclose(joints.velocity, 0.1)
    joints.step(jm.JointCommand(jm.MOVE, [0.9] * 6), 0.002)
    assert np.allclose(joints.velocity, 0.5)  # no faster than the limits
    joints.step(jm.JointCommand(jm.MOVE, [5.0] * 6), 10.0)
    assert np.allclose(joints.position, 1.0)  # never beyond them
    assert joints.protective_stop is None and not joints.effort.any()
    with pytest.raises(ValueError, match='HOLD, SERVO, MOVE, VELOCITY'):
        jm.JointCommand('SPEEDL')


def test_the_arm_holds_its_start_pose_until_a_controller_moves_it(arm):
    snapshot = run(arm, 1.0)
    assert np.array_equal(snapshot.position, START) and not snapshot.velocity.any()
    only(arm, 'joint_group_vel_controller')
    assert np.array_equal(run(arm, 0.5).position, START)


# -- controller_manager and controller_stopper ---------------------------------------------------

def test_switching_strict_and_best_effort(arm):
    def states():
        return {name: state for name, state, _, _, _ in arm.list_controllers()}
    before = states()
    ok, message = arm.switch_controllers(['no_such_controller'], ['scaled_pos_joint_traj_controller'], cm.STRICT)
    assert not ok and 'no_such_controller' in message and states() == before
    ok, message = arm.switch_controllers(['pos_joint_traj_controller'], [], cm.STRICT)
    assert not ok and 'conflict' in message
    ok, _ = arm.switch_controllers(['pos_joint_traj_controller'], ['scaled_pos_joint_traj_controller'], cm.STRICT)
    assert ok and states()['pos_joint_traj_controller'] == 'running'
    assert states()['scaled_pos_joint_traj_controller'] == 'stopped'
    reply = arm.trajectory_goal('scaled_pos_joint_traj_controller', 'g', JOINTS, [Point(1.0, HOME)])
    assert (reply.status, reply.code) == ('rejected', 'INVALID_GOAL')
    assert arm.load_controller('twist_controller') and not arm.load_controller('no_such_controller')
    types, bases = arm.controller_types()
    assert 'ros_controllers_cartesian/TwistController' in types and len(types) == len(bases)


def test_the_controller_stopper_follows_the_program(arm):
    arm.script_command('movej([0.1, -1.57, 1.57, -1.57, -1.57, 0])')
    arm.step(DT)
    assert not arm.robot.program_running and not arm.manager.running_commanding()
    ok, message = arm.switch_controllers(['pos_joint_traj_controller'], [], cm.STRICT)
    assert not ok and 'Robot control is currently inactive' in message
    run_until(arm, lambda: not arm.script_running, 5.0)
    assert arm.resend_robot_program()[0]
    arm.step(DT)
    assert [c.name for c in arm.manager.running_commanding()] == ['scaled_pos_joint_traj_controller']


# -- set_mode, program, dashboard ------------------------------------------------------------------

def set_mode(core, target, stop_program=False, play_program=False, seconds=10.0):
    run_ = core.set_mode(target, stop_program, play_program)
    clock = 0.0
    while clock < seconds:
        result = run_.poll(clock)
        if result is not None:
            return result
        core.step(0.01)
        clock += 0.01
    raise AssertionError('set_mode %s did not end' % target)


@pytest.mark.parametrize('headless', [True, False])
def test_set_mode_powers_on_releases_the_brakes_and_plays(configured_model, headless):
    core = make_core(configured_model, **{'~robot_mode': 'POWER_OFF', '~headless_mode': headless})
    assert core.robot.robot_mode == rs.POWER_OFF and not core.robot.program_running
    assert set_mode(core, rs.RUNNING, play_program=True) == (True, 'Reached target robot mode.')
    assert core.robot.robot_mode == rs.RUNNING and core.robot.program_running
    core.step(DT)
    assert [c.name for c in core.manager.running_commanding()] == ['scaled_pos_joint_traj_controller']
    assert set_mode(core, rs.IDLE, stop_program=True) == (True, 'Reached target robot mode.')
    assert core.robot.robot_mode == rs.IDLE and not core.robot.program_running


def test_set_mode_refuses_what_robot_state_helper_refuses(arm):
    assert set_mode(arm, None) == (False, 'Requested illegal mode.')
    success, message = set_mode(arm, 'BACKDRIVE')
    assert not success and 'cannot be explicitly selected' in message
    # Stopping a program that does not run fails the dashboard call, and robot_state_helper with it.
    arm.dashboard('stop')
    success, message = set_mode(arm, rs.IDLE, stop_program=True)
    assert not success and 'returned non-success: Failed to execute: stop' in message


def test_pause_holds_the_arm_and_play_resumes(arm):
    reply = arm.trajectory_goal('scaled_pos_joint_traj_controller', 'g', JOINTS, [Point(1.5, AWAY)])
    assert reply.status == 'accepted'
    run(arm, 0.5)
    assert arm.dashboard('pause') == 'Pausing program'
    snapshot = run(arm, 0.1)
    assert snapshot.speed_scaling == 0.0
    held = snapshot.position
    assert np.array_equal(run(arm, 1.0).position, held) and not finished(arm)
    assert arm.dashboard('play') == 'Starting program'
    run_until(arm, lambda: arm.finished, 3.0)
    assert finished(arm) == [('scaled_pos_joint_traj_controller', 'g', 'succeeded', 'SUCCESSFUL')]
    assert np.allclose(run(arm, 0.3).position, AWAY, atol=1e-3)


# -- the trajectory controllers ----------------------------------------------------------------------

def test_a_goal_succeeds_and_a_new_one_preempts(arm):
    controller = 'scaled_pos_joint_traj_controller'
    assert arm.trajectory_goal(controller, 'a', JOINTS, [Point(2.0, AWAY)]).status == 'accepted'
    run(arm, 0.5)
    assert arm.trajectory_goal(controller, 'b', JOINTS, [Point(1.0, HOME)]).status == 'accepted'
    assert finished(arm) == [(controller, 'a', 'preempted', 'SUCCESSFUL')]
    run_until(arm, lambda: arm.finished, 3.0)
    assert finished(arm) == [(controller, 'b', 'succeeded', 'SUCCESSFUL')]
    assert np.allclose(run(arm, 0.3).position, HOME, atol=1e-3)
    assert arm.trajectory_goal(controller, 'c', JOINTS, [Point(2.0, AWAY)]).status == 'accepted'
    run(arm, 0.3)
    arm.cancel_goal(controller, 'c')
    assert finished(arm) == [(controller, 'c', 'preempted', 'SUCCESSFUL')]
    stopped = run(arm, 1.0).position  # stop_trajectory_duration 0.5 s, and servoj's settling
    assert np.allclose(run(arm, 0.5).position, stopped, atol=1e-9)


def test_a_stall_of_the_host_on_the_wall_clock_is_not_the_arm_falling_behind(configured_model):
    # A ur3 (8 ms cycles) on a trajectory at its velocity limit: 3 rad in 1 s. The host stalls for ten
    # periods in the middle of it; the node makes the time up in the robot's own cycles.
    def goal_through_a_stall(cycles):
        arm = make_core(configured_model, 'ur3')
        controller = 'scaled_pos_joint_traj_controller'
        assert arm.trajectory_goal(controller, 'far', JOINTS, [Point(1.0, [3.0] + HOME[1:])]).status == 'accepted'
        run(arm, 0.4, dt=0.008)
        for dt in cycles:
            arm.step(dt)
        run_until(arm, lambda: arm.finished, 3.0, dt=0.008)
        return finished(arm)

    made_up = goal_through_a_stall(sim_clock.wall_cycles(0.08, 0.008, 0.08))
    assert made_up == [('scaled_pos_joint_traj_controller', 'far', 'succeeded', 'SUCCESSFUL')]
    # One 80 ms cycle instead: the trajectory runs 80 ms ahead of joints moving at 3 rad/s.
    at_once = goal_through_a_stall([0.08])
    assert at_once == [('scaled_pos_joint_traj_controller', 'far', 'aborted', 'PATH_TOLERANCE_VIOLATED')]


def test_a_goal_naming_an_extra_unknown_joint_is_invalid_joints(arm):
    reply = arm.trajectory_goal('scaled_pos_joint_traj_controller', 'x', JOINTS + ['wrist_4_joint'],
                                [Point(1.0, HOME + [0.0])])
    assert (reply.status, reply.code) == ('rejected', 'INVALID_JOINTS') and 'wrist_4_joint' in reply.message


def test_a_goal_ending_at_rest_outside_the_goal_tolerance_fails(arm):
    # The unscaled controller runs on while the paused robot stands still (controllers.md warns of
    # it): with the path tolerance switched off, the trajectory ends with the arm at rest far from it.
    only(arm, 'pos_joint_traj_controller')
    assert arm.dashboard('pause') == 'Pausing program'
    off = [JointTolerance(name, -1.0, 0.0, 0.0) for name in JOINTS]
    reply = arm.trajectory_goal('pos_joint_traj_controller', 'g', JOINTS, [Point(0.5, AWAY)], path_tolerance=off)
    assert reply.status == 'accepted'
    run_until(arm, lambda: arm.finished, 3.0)
    assert finished(arm) == [('pos_joint_traj_controller', 'g', 'aborted', 'GOAL_TOLERANCE_VIOLATED')]
    assert np.array_equal(arm.motion.position, START) and not arm.motion.velocity.any()


def test_pass_through_controllers_accept_then_abort_what_they_refuse(arm):
    only(arm, 'forward_joint_traj_controller')
    reply = arm.trajectory_goal('forward_joint_traj_controller', 'g', JOINTS[:5], [Point(1.0, HOME[:5])])
    assert (reply.status, reply.code) == ('aborted', 'INVALID_JOINTS')


def test_an_empty_trajectory_stops_and_succeeds(arm):
    arm.trajectory_goal('scaled_pos_joint_traj_controller', 'g', JOINTS, [Point(2.0, AWAY)])
    run(arm, 0.3)
    reply = arm.trajectory_goal('scaled_pos_joint_traj_controller', 'stop', JOINTS, [])
    assert reply.status == 'succeeded'
    assert finished(arm) == [('scaled_pos_joint_traj_controller', 'g', 'preempted', 'SUCCESSFUL')]


def test_query_state_samples_the_trajectory_ahead(arm):
    arm.trajectory_goal('scaled_pos_joint_traj_controller', 'g', JOINTS, [Point(1.0, AWAY)])
    arm.step(DT)
    position, velocity, _ = arm.query_state('scaled_pos_joint_traj_controller', 0.5)
    assert np.allclose(position, np.array(START) + (np.array(AWAY) - START) * (0.5 + DT), atol=1e-6)
    only(arm, 'pos_joint_traj_controller')
    assert arm.query_state('scaled_pos_joint_traj_controller', 0.0) is None


def test_a_cartesian_goal_follows_the_path_to_its_target(arm):
    only(arm, 'pose_based_cartesian_traj_controller')
    reply, start = arm.cartesian_goal_start('pose_based_cartesian_traj_controller')
    assert reply is None
    target = arm.arm.forward(start)
    target[:3, 3] += [0.05, -0.03, 0.04]
    points = arm.cartesian_points([Waypoint(1.0, tuple(target[:3, 3]), tuple(mat2quat(target[:3, :3])))], start)
    assert arm.trajectory_goal('pose_based_cartesian_traj_controller', 'c', JOINTS, points).status == 'accepted'
    run_until(arm, lambda: arm.finished, 3.0)
    assert finished(arm) == [('pose_based_cartesian_traj_controller', 'c', 'succeeded', 'SUCCESSFUL')]
    run(arm, 0.3)
    assert np.allclose(tool_pose(arm), target, atol=1e-5)


# -- velocity and twist ------------------------------------------------------------------------

def test_joint_group_velocity_moves_at_the_commanded_speed(arm):
    only(arm, 'joint_group_vel_controller')
    arm.group_velocity_command('joint_group_vel_controller', [0.1, 0, 0, 0, 0, 0])
    snapshot = run(arm, 1.0)
    assert snapshot.position[0] == pytest.approx(0.1, abs=1e-9) and snapshot.velocity[0] == pytest.approx(0.1)
    arm.group_velocity_command('joint_group_vel_controller', [0.1, 0, 0])
    assert 'Dimension of command (3)' in arm.take_messages()[-1][1]


def test_an_angular_twist_turns_the_tool_about_itself(arm):
    only(arm, 'twist_controller')
    start = tool_pose(arm)
    arm.twist_command('twist_controller', [0.0, 0.0, 0.0, 0.0, 0.0, 0.2])
    run(arm, 1.0)
    arm.twist_command('twist_controller', [0.0] * 6)
    pose = tool_pose(arm)
    turn = np.array([[math.cos(0.2), -math.sin(0.2), 0.0], [math.sin(0.2), math.cos(0.2), 0.0], [0.0, 0.0, 1.0]])
    assert np.allclose(pose[:3, :3], turn.dot(start[:3, :3]), atol=1e-6)
    assert np.allclose(pose[:3, 3], start[:3, 3], atol=1e-6)


# -- URScript -------------------------------------------------------------------------------------

def test_script_outputs_show_on_io_states_by_their_pin_numbers(arm):
    arm.script_command('sec io():\n  set_configurable_digital_out(2, True)\n  set_tool_digital_out(1, True)\n'
                       '  set_standard_digital_out(7, True)\n  set_standard_analog_out(1, 0.25)\nend')
    snapshot = arm.step(DT)
    # io_states numbers them 0-7 standard, 8-15 configurable, 16-17 tool.
    assert [pin for pin, on in enumerate(snapshot.digital_out) if on] == [7, 10, 17]
    assert snapshot.analog_out == [0.0, 0.25]
    assert arm.robot.program_running  # a secondary program runs beside the External Control program


def test_an_io_function_given_a_string_for_a_number_stops_with_the_robots_type_error(arm):
    for call, words in (('set_standard_digital_out("half ", True)', 'set_standard_digital_out takes a number, '
                                                                      'not string'),
                        ('set_standard_analog_out(0, "1 V")', 'set_standard_analog_out takes a number, not string'),
                        ('x = get_standard_digital_in([1])', 'get_standard_digital_in takes a number, not list')):
        arm.script_command('def p():\n  %s\nend' % call)
        run(arm, 2 * DT)
        level, text = arm.take_messages()[-1]
        assert level == arm_core.ERROR and 'Runtime error in line 2' in text and 'Type error: ' + words in text, text


def test_the_general_purpose_registers_take_the_manuals_addresses_and_values(arm):
    arm.robot.registers.write('input', 'integer', 47, 7)
    arm.script_command('def p():\n  write_output_integer_register(0, read_input_integer_register(47) * 6)\n'
                       '  write_output_boolean_register(127, True)\n  write_output_float_register(47, 0.5)\nend')
    run(arm, 2 * DT)
    assert arm.robot.registers.output['integer'][0] == 42
    assert arm.robot.registers.output['boolean'][127] is True
    assert arm.robot.registers.output['float'][47] == 0.5
    for call, problem in (('write_output_integer_register(48, 1)', 'integer register 48 does not exist'),
                          ('write_output_integer_register(0, 2147483648)', '32-bit signed integer'),
                          ('write_output_boolean_register(0, 1)', 'True or False'),
                          ('read_input_float_register(-1)', 'float register -1 does not exist')):
        arm.script_command('def p():\n  %s\nend' % call)
        run(arm, 2 * DT)
        level, text = arm.take_messages()[-1]
        assert level == arm_core.ERROR and problem in text and call.split('(')[0] in text, text


def test_movej_without_a_and_v_takes_the_manuals_default_profile(arm):
    # URScript manual: movej(q, a=1.4, v=1.05, ...). 1 rad on the leading joint is longer than
    # the ramps' v^2/a: accelerate, cruise at v, decelerate: 1/v + v/a seconds.
    target = list(START)
    target[0] += 1.0
    arm.script_command('movej([%s])' % number_list(target))
    took = run_until(arm, lambda: not arm.script_running, 5.0)
    assert took == pytest.approx(1.0 / 1.05 + 1.05 / 1.4, abs=2 * DT)
    assert np.allclose(arm.motion.position, target)
    assert arm.robot.program_state == rs.STOPPED and not arm.robot.program_running


def test_movej_to_a_pose_and_sleep(arm):
    pose = tool_pose(arm)
    pose[:3, 3] += [0.0, 0.05, 0.0]
    ur_pose = tuple(pose[:3, 3]) + tuple(rotation_vector(pose[:3, :3]))
    arm.script_command('def p():\n  sleep(0.5)\n  movej(p[%s], t=2)\nend' % number_list(ur_pose))
    run(arm, 0.45)
    assert np.array_equal(arm.motion.position, START)  # still sleeping
    took = run_until(arm, lambda: not arm.script_running, 5.0)
    assert took == pytest.approx(0.05 + 2.0, abs=3 * DT)  # t=2 stretches the short move to 2 s
    assert np.allclose(tool_pose(arm), pose, atol=1e-5)


def test_scripts_the_robot_would_not_compile_change_nothing(arm):
    for script, line in (('movej([0, 0, 0]', 1), ('def p():\n  sleep(1)\n', 2),
                         ('sec s():\n  movej([%s])\nend' % number_list(START), 2),
                         ('def p():\n  x = 1\n  frobnicate(x)\nend', 3)):
        arm.script_command(script)
        level, text = arm.take_messages()[-1]
        assert level == arm_core.ERROR and 'would not compile' in text and '\n' not in text
        assert 'line %d' % line in text, text
        assert arm.robot.program_running and not arm.script_running


def test_a_runtime_error_stops_the_program_with_the_robots_runtime_exception(arm):
    for script in ('def p():\n  movej([0, 0, 0])\nend', 'def p():\n  set_tool_digital_out(1)\nend',
                   'def p():\n  a = [1, 2]\n  b = a[2]\nend'):
        arm.script_command(script)
        run(arm, 2 * DT)
        level, text = arm.take_messages()[-1]
        assert level == arm_core.ERROR and 'program stopped' in text and '\n' not in text, text
        assert arm.robot.log[-1] in text
        assert not arm.script_running and arm.robot.program_state == rs.STOPPED
        assert np.array_equal(arm.motion.position, START)


def test_a_program_replaces_external_control_and_play_resumes_it(arm):
    arm.script_command('def p():\n  movel(pose_trans(get_actual_tcp_pose(), p[0, 0, 0.02, 0, 0, 0]), a=0.5, v=0.1)\nend')
    run(arm, DT)
    assert arm.script_running and not arm.robot.program_running
    run_until(arm, lambda: not arm.script_running, 5.0)
    assert arm.dashboard('play').startswith('Starting program')
    run(arm, 0.1)
    assert arm.robot.program_running


def test_a_secondary_program_runs_beside_and_may_not_move(arm):
    arm.script_command('sec s():\n  movel(p[0.3, 0.1, 0.3, 0, 3.14, 0])\nend')
    level, text = arm.take_messages()[-1]
    assert level == arm_core.ERROR and 'would not compile' in text and 'line 2' in text
    arm.script_command('sec s():\n  textmsg("beside")\nend')
    run(arm, DT)
    assert arm.robot.log[-1] == 'beside' and arm.robot.program_running


def test_threads_run_beside_the_program_each_control_cycle(arm):
    arm.script_command('def p():\n  global n = 0\n  thread count():\n    while True:\n      n = n + 1\n'
                       '      sync()\n    end\n  end\n  h = run count()\n  sleep(0.1)\n  kill h\n'
                       '  textmsg("counted ", n)\nend')
    run_until(arm, lambda: not arm.script_running, 1.0)
    counted = int(arm.robot.log[-1].split()[-1])
    assert abs(counted - 0.1 / DT) <= 1  # once per 2 ms cycle


def test_force_mode_without_physics_runs_the_compliant_axis_at_its_speed_limit(arm):
    # Nothing pushes back on the kinematic arm: as in URSim, the tool goes at the limit (tool z points down).
    start = tool_pose(arm)[:3, 3]
    arm.script_command('def p():\n  force_mode(get_actual_tcp_pose(), [0, 0, 1, 0, 0, 0], [0, 0, 10, 0, 0, 0], 2, '
                       '[0.1, 0.1, 0.02, 0.17, 0.17, 0.17])\n  sleep(1)\n  end_force_mode()\nend')
    run(arm, 0.5)
    middle = tool_pose(arm)[:3, 3]
    run(arm, 0.25)
    speed = (middle - tool_pose(arm)[:3, 3]) / 0.25
    assert speed[2] == pytest.approx(0.02, rel=0.01)
    assert np.allclose(speed[:2], 0.0, atol=1e-6) and np.allclose(middle[:2], start[:2], atol=1e-6)
    assert arm.tcp_force()[0] == pytest.approx(np.zeros(6))


def test_force_mode_near_a_wrist_singularity_reaches_what_the_inverse_kinematics_reaches(arm):
    # wrist_2 a milliradian off 0, where wrist_1's and wrist_3's axes line up: there force mode's nanometre
    # reach does not converge, and the inverse kinematics' default reach still takes the pose.
    arm.script_command('def p():\n  movej([0.3, -1.4, 1.6, -1.8, 0.001, 0.2], a=3, v=3)\n'
                       '  force_mode(get_actual_tcp_pose(), [0, 0, 1, 0, 0, 0], [0, 0, 10, 0, 0, 0], 2, '
                       '[0.1, 0.1, 0.02, 0.17, 0.17, 0.17])\n  sleep(1)\n  end_force_mode()\nend')
    run_until(arm, lambda: arm.script_robot.force is not None, 5.0)
    start = tcp_pose(arm)[:3, 3]
    run(arm, 0.25)
    assert arm.script_running and arm.take_messages() == []
    assert np.linalg.norm(tcp_pose(arm)[:3, 3] - start) > 0.001  # it moves


def test_the_robot_log_keeps_only_its_latest_entries(arm):
    for i in range(rs.LOG_ENTRIES + 50):
        arm.script_command('sec log():\n  textmsg("line %d %s")\nend' % (i, 'x' * 2000))
    assert len(arm.robot.log) == rs.LOG_ENTRIES
    assert arm.robot.log[-1].startswith('line %d ' % (rs.LOG_ENTRIES + 49))
    assert max(len(entry) for entry in arm.robot.log) == rs.LOG_ENTRY_CHARACTERS
    assert arm.take_messages()[-1][0] == arm_core.INFO


# -- protective stop -------------------------------------------------------------------------------

class StoppingJoints(jm.KinematicJoints):
    """The kinematic joints that stop the robot when told to, as a physics engine's would on a collision."""

    stop_next = None

    def step(self, command, dt):
        super(StoppingJoints, self).step(command, dt)
        self.protective_stop, self.stop_next = self.stop_next, None


def test_a_protective_stop_stops_the_arm_until_unlocked_and_played(configured_model):
    core = make_core(configured_model, motion=StoppingJoints.from_settings)
    controller = 'scaled_pos_joint_traj_controller'
    core.trajectory_goal(controller, 'g', JOINTS, [Point(2.0, AWAY)])
    run(core, 0.5)
    core.motion.stop_next = 'collision of the wrist'
    snapshot = core.step(DT)
    assert (snapshot.safety_mode, core.robot.program_state) == (rs.PROTECTIVE_STOP, rs.PAUSED)
    assert snapshot.program_running and snapshot.speed_scaling == 0.0
    assert 'collision of the wrist' in core.take_messages()[-1][1]
    held = run(core, 0.1).position
    assert np.array_equal(run(core, 2.0).position, held) and not finished(core)
    assert core.dashboard('unlock protective stop') == rs.UNLOCK_TOO_EARLY
    assert core.dashboard('play') == 'Failed to execute: play'
    run(core, 3.0)
    assert core.dashboard('unlock protective stop') == 'Protective stop releasing'
    assert core.robot.safety_mode == rs.SAFETY_NORMAL
    assert np.array_equal(run(core, 0.5).position, held)  # still paused
    assert core.dashboard('play') == 'Starting program'
    run_until(core, lambda: core.finished, 3.0)
    assert finished(core) == [(controller, 'g', 'succeeded', 'SUCCESSFUL')]
    assert np.allclose(run(core, 0.3).position, AWAY, atol=1e-3)


def test_set_mode_unlocks_a_protective_stop(configured_model):
    core = make_core(configured_model, motion=StoppingJoints.from_settings)
    core.motion.stop_next = 'collision'
    core.step(DT)
    success, message = set_mode(core, rs.RUNNING, play_program=True)
    assert not success and message.endswith(rs.UNLOCK_TOO_EARLY)
    run(core, rs.UNLOCK_DELAY + 0.1, dt=0.01)
    assert set_mode(core, rs.RUNNING, play_program=True) == (True, 'Reached target robot mode.')
    assert core.robot.safety_mode == rs.SAFETY_NORMAL and core.robot.program_state == rs.PLAYING


# -- what is published ----------------------------------------------------------------------------

def test_the_snapshot_is_what_the_driver_publishes(arm):
    assert arm.set_speed_slider(0.5)[0] and not arm.set_speed_slider(1.5)[0]
    snapshot = arm.step(DT)
    assert snapshot.speed_scaling == 0.5 and snapshot.reading == set(arm_core.READ_ONLY)
    assert np.allclose(snapshot.tool_pose, arm.arm.forward(START))
    assert [name for name, _, _ in snapshot.controller_states] == ['scaled_pos_joint_traj_controller']
    assert (snapshot.robot_mode, snapshot.safety_mode, snapshot.program_running) == (rs.RUNNING, rs.SAFETY_NORMAL,
                                                                                     True)
    ok, _ = arm.switch_controllers([], ['force_torque_sensor_controller'], cm.STRICT)
    assert ok and 'force_torque_sensor_controller' not in arm.step(DT).reading
    assert arm.set_io(1, 3, 1.0)[0] and arm.step(DT).digital_out[3]
    assert not arm.set_io(1, 40, 1.0)[0] and 'set_io' in arm.take_messages()[-1][1]


# -- blends -------------------------------------------------------------------------------------------

def square_program(r):
    """Three movel around three corners of a 4 cm square in the tool's plane, each blended with `r`."""
    return ('def square():\n  start = get_actual_tcp_pose()\n'
            '  movel(pose_add(start, p[0.04, 0, 0, 0, 0, 0]), a=0.5, v=0.1, r=%s)\n'
            '  movel(pose_add(start, p[0.04, 0.04, 0, 0, 0, 0]), a=0.5, v=0.1, r=%s)\n'
            '  movel(pose_add(start, p[0, 0.04, 0, 0, 0, 0]), a=0.5, v=0.1)\n'
            'end' % (number(r), number(r)))


def test_three_blended_moves_run_through_when_their_blends_do_not_overlap(arm):
    start = tool_pose(arm)[:3, 3]
    arm.script_command(square_program(0.01))
    run_until(arm, lambda: not arm.script_running, 10.0)
    assert arm.robot.program_state == rs.STOPPED
    assert not [text for level, text in arm.take_messages() if level == arm_core.ERROR]
    # pose_add moves the TCP in the robot's base frame; the third corner is 4 cm along its y from the start.
    moved = tool_pose(arm)[:3, 3] - start
    assert np.linalg.norm(moved) == pytest.approx(0.04, abs=1e-4) and abs(moved[2]) < 1e-4


def test_overlapping_blends_stop_the_program_naming_both_radii(arm):
    # 3 cm at each corner on 4 cm sides: the two blends would overlap, which the robot refuses.
    arm.script_command(square_program(0.03))
    run_until(arm, lambda: not arm.script_running, 10.0)
    errors = [text for level, text in arm.take_messages() if level == arm_core.ERROR]
    assert errors and 'overlapping blends' in errors[-1] and 'r=0.03' in errors[-1], errors


def test_the_dashboards_stop_ends_a_program_and_play_starts_external_control_not_it(arm):
    arm.script_command('def p():\n  movel(pose_add(get_actual_tcp_pose(), p[0, 0, 0.1, 0, 0, 0]), a=0.5, v=0.02)\nend')
    run(arm, 0.5)
    assert arm.script_running
    assert arm.dashboard('stop') == 'Stopped'
    run(arm, DT)
    stopped_at = np.array(arm.motion.position)
    assert not arm.script_running and arm.robot.program_state == rs.STOPPED
    assert arm.dashboard('play').startswith('Starting program')
    run(arm, 0.5)
    assert arm.robot.program_running
    # External Control holds where the program was stopped: the program does not move the arm any more.
    assert np.allclose(arm.motion.position, stopped_at, atol=1e-6)


def test_a_motion_that_fails_while_moving_names_the_line_of_its_call(arm):
    # speedj on into the shoulder's position limit: the robot stops, and its runtime error names the call.
    arm.script_command('def p():\n  textmsg("going")\n  speedj([3.0, 0, 0, 0, 0, 0], 5, 10)\nend')
    run_until(arm, lambda: not arm.script_running, 10.0)
    errors = [text for level, text in arm.take_messages() if level == arm_core.ERROR]
    assert errors and 'position limit' in errors[-1] and 'line 3, column 3' in errors[-1], errors
