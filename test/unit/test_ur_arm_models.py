"""Pure models behind the simulated UR arm (no ROS master): trajectories, controllers, modes."""
import math
import os

import numpy as np
import pytest
import rospkg

from ur3_ft_gripper_description.devices.ur_arm import controller_manager as cm
from ur3_ft_gripper_description.devices.ur_arm import robot_state as rs
from ur3_ft_gripper_description.devices.ur_arm import software
from ur3_ft_gripper_description.devices.ur_arm.trajectory import GoalError, Point, Spline, Tolerances, stop_spline
from ur3_ft_gripper_description.devices.ur_arm.trajectory_controller import TrajectoryController

JOINTS = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
          'wrist_3_joint']
LOWER, UPPER = [-2 * math.pi] * 6, [2 * math.pi] * 6
VMAX = [math.pi] * 6


def controllers_yaml(ur_type):
    return os.path.join(rospkg.RosPack().get_path('ur_robot_driver'), 'config', '%s_controllers.yaml' % ur_type)


def controller_config(ur_type):
    """ur_robot_driver's controller sections for `ur_type` and its joints, as the simulated arm reads them."""
    return cm.controller_sections(cm.read_config(controllers_yaml(ur_type)))


def jtc(name='scaled_pos_joint_traj_controller', ur_type='ur5e', vmax=VMAX):
    sections, joints = controller_config(ur_type)
    section = sections[name]
    return TrajectoryController(joints, section['constraints'], section['stop_trajectory_duration'],
                                'Scaled' in section['type'], LOWER, UPPER, vmax)


def run(controller, seconds, position, dt=0.002, scaling=1.0):
    """Perfect position tracking for `seconds`; (position, outcomes)."""
    position = np.asarray(position, dtype=float)
    velocity = np.zeros(6)
    outcomes = []
    for _ in range(int(round(seconds / dt))):
        command, _, done = controller.update(dt, scaling, position, velocity)
        velocity = (command - position) / dt
        position = command
        outcomes += done
    return position, outcomes


def assert_refused(code, text, call):
    with pytest.raises(GoalError) as caught:
        call()
    assert caught.value.code == code, caught.value
    assert text in str(caught.value), caught.value


# -- splines -------------------------------------------------------------------

def test_spline_kinds_follow_the_points_data():
    times = [0.0, 1.0, 2.0]
    positions = [[0.0], [1.0], [0.0]]
    linear = Spline(times, positions)
    assert linear.kind == 'linear'
    assert linear.sample(0.5)[0][0] == pytest.approx(0.5)
    cubic = Spline(times, positions, [[0.0], [0.0], [0.0]])
    assert cubic.kind == 'cubic'
    # A cubic from rest to rest: half way at half time, still at the ends.
    assert cubic.sample(0.5)[0][0] == pytest.approx(0.5)
    assert cubic.sample(1.0)[1][0] == pytest.approx(0.0, abs=1e-9)
    quintic = Spline(times, positions, [[0.0]] * 3, [[0.0]] * 3)
    assert quintic.kind == 'quintic'
    p, v, a = quintic.sample(1.0 - 1e-9)
    assert p[0] == pytest.approx(1.0) and v[0] == pytest.approx(0.0, abs=1e-6) and a[0] == pytest.approx(-60 / 6.0 * 1, rel=1)


def test_spline_meets_every_point_and_holds_after_the_end():
    rng = np.random.default_rng(3)
    times = np.cumsum(rng.uniform(0.2, 1.0, 5))
    positions, velocities, accelerations = (rng.uniform(-1, 1, (5, 6)) for _ in range(3))
    spline = Spline(times, positions, velocities, accelerations)
    for t, p, v, a in zip(times[1:], positions[1:], velocities[1:], accelerations[1:]):
        sp, sv, sa = spline.sample(t - 1e-9)
        assert np.allclose(sp, p, atol=1e-6) and np.allclose(sv, v, atol=1e-5) and np.allclose(sa, a, atol=1e-3)
    after = spline.sample(times[-1] + 5.0)
    assert np.allclose(after[0], positions[-1]) and not after[1].any()


def test_stop_comes_to_rest_within_stop_trajectory_duration():
    spline = stop_spline(0.0, [0.0] * 6, [1.0] * 6, 0.5)
    p, v, _ = spline.sample(0.5)
    assert np.allclose(v, 0.0) and np.allclose(p, 0.25)


# -- goal validation -------------------------------------------------------------

def test_unknown_joint_is_invalid_joints():
    names = ['elbow_joint', 'shoulder_lift_joint', 'shoulder_pan_joint', 'wrist_1_joint', 'wrist_2_joint',
             'wrist_4_joint']
    assert_refused('INVALID_JOINTS', 'wrist_4_joint',
                   lambda: jtc().accept(1, names, [Point(1.0, [0] * 6)], 0.0, [0] * 6, [0] * 6))


def test_missing_and_repeated_joints_are_invalid_joints():
    assert_refused('INVALID_JOINTS', 'missing', lambda: jtc().accept(1, JOINTS[:5], [Point(1.0, [0] * 5)], 0.0,
                                                                     [0] * 6, [0] * 6))
    assert_refused('INVALID_JOINTS', 'repeat', lambda: jtc().accept(
        1, JOINTS[:5] + JOINTS[:1], [Point(1.0, [0] * 6)], 0.0, [0] * 6, [0] * 6))


@pytest.mark.parametrize('points, text', [
    ([Point(6.0, [0] * 6), Point(3.0, [-0.5] * 6)], 'strictly increasing'),
    ([Point(1.0, [0] * 6), Point(1.0, [0.1] * 6)], 'strictly increasing'),
    ([Point(1.0, [0] * 5)], '5 positions'),
    ([Point(1.0, [0] * 6, velocities=[0] * 3)], 'velocities'),
    ([Point(1.0, [0, 0, float('nan'), 0, 0, 0])], 'NaN'),
    ([Point(1.0, [0, 0, 0, 0, 7.0, 0])], 'beyond its limits'),
    ([], 'no points'),
], ids=['decreasing', 'equal-times', 'short', 'velocity-size', 'nan', 'beyond-limits', 'empty'])
def test_bad_trajectories_are_invalid_goal(points, text):
    assert_refused('INVALID_GOAL', text, lambda: jtc().accept(1, JOINTS, points, 0.0, [0] * 6, [0] * 6))


def test_goal_in_any_joint_order_reaches_the_named_positions():
    controller = jtc()
    order = [2, 1, 0, 3, 4, 5]
    target = np.array([0.1, -0.2, 0.3, -0.4, 0.5, -0.6])
    controller.accept(1, [JOINTS[i] for i in order], [Point(1.0, target[order])], 0.0, [0] * 6, [0] * 6)
    position, outcomes = run(controller, 1.2, [0] * 6)
    assert np.allclose(position, target, atol=1e-6)
    assert [(o.goal_id, o.status, o.code) for o in outcomes] == [(1, 'succeeded', 'SUCCESSFUL')]


# -- execution ---------------------------------------------------------------------

def test_scaled_controller_runs_at_the_speed_scaling():
    controller = jtc()
    controller.accept(1, JOINTS, [Point(2.0, [0.4] * 6)], 0.0, [0] * 6, [0] * 6)
    position, outcomes = run(controller, 2.0, [0] * 6, scaling=0.5)
    assert position[0] == pytest.approx(0.2, abs=1e-3) and not outcomes  # half way at half speed
    position, outcomes = run(controller, 2.1, position, scaling=0.5)
    assert outcomes and outcomes[0].status == 'succeeded'


def test_paused_program_holds_the_scaled_trajectory():
    controller = jtc()
    controller.accept(1, JOINTS, [Point(1.0, [0.4] * 6)], 0.0, [0] * 6, [0] * 6)
    position, _ = run(controller, 0.5, [0] * 6)
    held, outcomes = run(controller, 3.0, position, scaling=0.0)
    assert np.allclose(held, position) and not outcomes


def test_unscaled_controller_ignores_the_scaling():
    controller = jtc('pos_joint_traj_controller')
    controller.accept(1, JOINTS, [Point(1.0, [0.4] * 6)], 0.0, [0] * 6, [0] * 6)
    _, outcomes = run(controller, 1.1, [0] * 6, scaling=0.1)
    assert outcomes and outcomes[0].status == 'succeeded'


def test_over_fast_trajectory_is_slowed_to_the_velocity_limits():
    # 3 rad in 0.5 s asks 6 rad/s (linear) of joints limited to pi rad/s.
    controller = jtc()
    controller.accept(1, JOINTS, [Point(0.5, [3.0] * 6)], 0.0, [0] * 6, [0] * 6)
    dt, position, fastest, outcomes = 0.002, np.zeros(6), 0.0, []
    for _ in range(2000):
        command, _, done = controller.update(dt, 1.0, position, np.zeros(6))
        fastest = max(fastest, np.max(np.abs(command - position)) / dt)
        position, outcomes = command, outcomes + done
        if outcomes:
            break
    assert fastest <= math.pi * 1.001
    assert controller.limit_factor <= 1.0
    assert outcomes and outcomes[0].status == 'succeeded'


def test_path_tolerance_ends_a_goal_the_joints_cannot_follow():
    controller = jtc('pos_joint_traj_controller')
    controller.accept(1, JOINTS, [Point(1.0, [0.4] * 6)], 0.0, [0] * 6, [0] * 6)
    position = np.zeros(6)  # joints stuck
    outcomes = []
    for _ in range(500):
        outcomes += controller.update(0.002, 1.0, position, np.zeros(6))[2]
    assert [(o.status, o.code) for o in outcomes] == [('aborted', 'PATH_TOLERANCE_VIOLATED')]


def test_goal_tolerance_after_goal_time():
    controller = jtc('pos_joint_traj_controller')
    controller.accept(1, JOINTS, [Point(0.1, [0.15] * 6)], 0.0, [0] * 6, [0] * 6)
    outcomes = []
    for _ in range(500):  # joints stay 0.15 rad away: within path (0.2), beyond goal (0.1)
        outcomes += controller.update(0.002, 1.0, np.zeros(6), np.zeros(6))[2]
    assert [(o.status, o.code) for o in outcomes] == [('aborted', 'GOAL_TOLERANCE_VIOLATED')]


def test_goal_tolerances_override_and_disable():
    tolerances = Tolerances.from_constraints(JOINTS, {'goal_time': 0.6, 'stopped_velocity_tolerance': 0.05,
                                                      'elbow_joint': {'trajectory': 0.2, 'goal': 0.1}})

    class JointTolerance(object):
        def __init__(self, name, position, velocity=0.0):
            self.name, self.position, self.velocity, self.acceleration = name, position, velocity, 0.0

    goal = tolerances.for_goal(JOINTS, [JointTolerance('elbow_joint', -1)], [JointTolerance('elbow_joint', 0.3)],
                               2.0)
    assert goal.path_position[2] == 0.0 and goal.goal_position[2] == 0.3 and goal.goal_time == 2.0
    assert tolerances.goal_position[2] == 0.1  # the controller's own stay


def test_new_goal_preempts_and_cancel_stops():
    controller = jtc()
    controller.accept(1, JOINTS, [Point(2.0, [0.4] * 6)], 0.0, [0] * 6, [0] * 6)
    position, _ = run(controller, 0.5, [0] * 6)
    preempted = controller.accept(2, JOINTS, [Point(2.0, [-0.4] * 6)], 0.0, position, [0] * 6)
    assert (preempted.goal_id, preempted.status) == (1, 'preempted')
    position, _ = run(controller, 0.5, position)
    outcome = controller.cancel(2, position, [0.2] * 6)
    assert (outcome.goal_id, outcome.status) == (2, 'preempted')
    stopped, outcomes = run(controller, 0.6, position)
    assert not outcomes
    still, _ = run(controller, 0.5, stopped)
    assert np.allclose(still, stopped)


def test_slowed_trajectory_with_goal_time_fails_without_succeeds():
    for goal_time, status in ((0.2, 'aborted'), (0.0, 'succeeded')):
        controller = jtc()
        controller.accept(1, JOINTS, [Point(1.0, [0.2] * 6)], 0.0, [0] * 6, [0] * 6, goal_time_tolerance=goal_time)
        _, outcomes = run(controller, 2.5, [0] * 6, scaling=0.5)
        assert outcomes and outcomes[0].status == status, outcomes


# -- controller manager --------------------------------------------------------------

STARTED = ['joint_state_controller', 'scaled_pos_joint_traj_controller', 'speed_scaling_state_controller',
           'force_torque_sensor_controller']


def manager(ur_type='ur5e'):
    sections, joints = controller_config(ur_type)
    return cm.ControllerManager(sections, joints, STARTED, [n for n in sections if n not in STARTED and
                                                            sections[n]['type'] in cm.SIMULATED_TYPES])


def states(m):
    return {name: state for name, state, _, _, _ in m.listing()}


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e', 'ur10e'])
def test_every_controller_of_the_config_is_loaded(ur_type):
    s = states(manager(ur_type))
    assert s['scaled_pos_joint_traj_controller'] == 'running'
    assert s['pos_joint_traj_controller'] == 'initialized'
    for name in ('twist_controller', 'pose_based_cartesian_traj_controller', 'forward_joint_traj_controller',
                 'joint_group_vel_controller', 'scaled_vel_joint_traj_controller'):
        assert name in s


def test_one_commanding_controller_holds_the_joints():
    m = manager()
    ok, message = m.switch(['pos_joint_traj_controller'], [], cm.STRICT)
    assert not ok and 'conflict' in message
    ok, _ = m.switch(['pos_joint_traj_controller'], ['scaled_pos_joint_traj_controller'], cm.STRICT)
    assert ok and [c.name for c in m.running_commanding()] == ['pos_joint_traj_controller']
    ok, _ = m.switch(['pos_joint_traj_controller'], [], cm.BEST_EFFORT)
    assert ok  # already running: skipped


def test_strict_fails_on_unknown_best_effort_skips():
    m = manager()
    before = states(m)
    ok, message = m.switch(['no_such_controller'], ['scaled_pos_joint_traj_controller'], cm.STRICT)
    assert not ok and 'no_such_controller' in message and states(m) == before
    ok, message = m.switch(['joint_group_vel_controller', 'no_such_controller'],
                           ['scaled_pos_joint_traj_controller', 'twist_controller'], cm.BEST_EFFORT)
    assert ok and states(m)['joint_group_vel_controller'] == 'running'
    assert states(m)['scaled_pos_joint_traj_controller'] == 'stopped'


def test_unknown_started_controller_is_one_line():
    sections, joints = controller_config('ur5e')
    with pytest.raises(cm.ControllerConfigError, match='not_there'):
        cm.ControllerManager(sections, joints, ['not_there'], [])


def test_controller_the_simulation_cannot_run_is_one_line():
    sections, joints = controller_config('ur5e')
    with pytest.raises(cm.ControllerConfigError, match='robot_status_controller.*not simulated'):
        cm.ControllerManager(sections, joints, STARTED + ['robot_status_controller'], [])


# -- robot modes, program, dashboard -------------------------------------------------

def new_robot(ur_type='ur5e', **kwargs):
    return rs.RobotState(software.for_model(ur_type), **kwargs)


def settle(robot, seconds=5.0):
    for _ in range(int(seconds / 0.05)):
        robot.step(0.05)


def test_power_on_brake_release_play():
    robot = new_robot(robot_mode=rs.POWER_OFF, program_running=False)
    assert robot.speed_scaling() == 0.0
    assert robot.dashboard('play') == 'Failed to execute: play'
    assert robot.dashboard('power on') == 'Powering on'
    settle(robot)
    assert robot.robot_mode == rs.IDLE
    assert robot.dashboard('brake release') == 'Brake releasing'
    settle(robot)
    assert robot.robot_mode == rs.RUNNING and not robot.program_running
    assert robot.dashboard('play') == 'Starting program'
    assert robot.program_running and robot.speed_scaling() == 1.0
    assert robot.dashboard('pause') == 'Pausing program' and robot.speed_scaling() == 0.0
    assert robot.dashboard('power off') == 'Powering off' and not robot.program_running


def test_slider_and_io():
    robot = new_robot()
    assert robot.set_speed_slider(0.3)[0] and robot.speed_scaling() == 0.3
    assert not robot.set_speed_slider(1.5)[0] and not robot.set_speed_slider(float('nan'))[0]
    assert robot.set_io(1, 2, 1.0)[0] and robot.digital_out[2]
    assert not robot.set_io(1, 18, 1.0)[0]
    assert not robot.set_io(9, 0, 1.0)[0]
    assert not robot.set_io(2, 0, 1.0)[0]  # FUN_SET_FLAG: not implemented by ur_robot_driver
    assert robot.set_io(1, 5, 0.5)[0] and robot.digital_out[5]  # sent as a bool
    assert robot.set_io(4, 0, 24.0)[0] and robot.tool_voltage == 24


def test_script_and_resend_in_headless_mode():
    robot = new_robot(headless=True)
    assert robot.program_running
    robot.script_started(secondary=True)
    assert robot.program_running
    robot.script_started(secondary=False)
    assert not robot.program_running
    assert robot.resend_robot_program()[0] and robot.program_running
    assert robot.hand_back_control()[0] and not robot.program_running
    assert robot.hand_back_control() == (True, 'No control active. Nothing to do.')


def test_resend_without_headless_mode():
    # The simulated controller has no teach pendant: resend starts External Control in either mode.
    robot = new_robot(headless=False)
    robot.script_started(secondary=False)
    assert not robot.program_running
    assert robot.resend_robot_program() == (True, 'Successfully resent robot program') and robot.program_running
    robot.dashboard('power off')
    assert not robot.resend_robot_program()[0]


def test_dashboard_answers():
    robot = new_robot()
    assert robot.dashboard('robotmode') == 'Robotmode: RUNNING'
    assert robot.dashboard('load nothing.urp') == 'File not found: nothing.urp'
    assert robot.dashboard('load external_control.urp') == 'Loading program: external_control.urp'
    assert robot.dashboard('addToLog hello') == 'Added log message' and list(robot.log) == ['hello']
    assert robot.dashboard('frobnicate') == "could not understand: 'frobnicate'"


def test_set_mode_plans():
    assert rs.plan_set_mode(rs.POWER_OFF, rs.RUNNING, False) == [('power on', rs.IDLE),
                                                                  ('brake release', rs.RUNNING)]
    assert rs.plan_set_mode(rs.RUNNING, rs.IDLE, True) == [('stop', None), ('power off', rs.POWER_OFF),
                                                           ('power on', rs.IDLE)]
    # Already there: robot_state_helper sends nothing, stop_program included.
    assert rs.plan_set_mode(rs.RUNNING, rs.RUNNING, True) == []
    with pytest.raises(ValueError, match='cannot be explicitly selected'):
        rs.plan_set_mode(rs.RUNNING, 'BACKDRIVE', False)


# -- the arm's kinematics from the model ------------------------------------------------

def test_jacobian_and_inverse_kinematics_agree_with_the_model(configured_model):
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics, pose_error
    model = configured_model('ur5e', True, True)
    arm = ArmKinematics(model.text, JOINTS)
    home = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])
    # tool0_controller is the model's own tool0 in base.
    assert np.allclose(arm.forward(home), model.transform('base', 'tool0', dict(zip(JOINTS, home))), atol=1e-9)
    numeric = np.array([pose_error(arm.forward(home + 1e-6 * np.eye(6)[j]), arm.forward(home)) / 1e-6
                        for j in range(6)]).T
    assert np.allclose(numeric, arm.jacobian(home), atol=1e-5)
    target = arm.forward(home)
    target[:3, 3] += [0.05, -0.03, 0.04]
    solution = arm.inverse(target, home)
    assert solution is not None and np.allclose(arm.forward(solution), target, atol=1e-5)
    far = np.eye(4)
    far[:3, 3] = [5.0, 0.0, 0.5]
    assert arm.inverse(far, home) is None


def test_the_jacobian_of_a_tcp_moves_with_that_point(configured_model):
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics, pose_error
    arm = ArmKinematics(configured_model('ur3', True, True).text, JOINTS)
    tcp = np.eye(4)
    tcp[:3, 3] = [0.01, -0.02, 0.2]
    q = np.array([0.3, -1.2, 1.4, -1.8, -1.5, 0.4])
    numeric = np.array([pose_error(arm.forward(q + 1e-6 * np.eye(6)[j]).dot(tcp), arm.forward(q).dot(tcp)) / 1e-6
                        for j in range(6)]).T
    assert np.allclose(numeric, arm.jacobian(q, tcp), atol=1e-5)


@pytest.mark.parametrize('selection', [[0, 0, 1, 0, 0, 0], [1, 0, 1, 0, 0, 1]])
def test_force_mode_on_servos_that_give_pulls_along_the_compliant_axes_only(configured_model, selection):
    """The servos' pull (stiffness times joint offset: torques) towards a target ahead of the TCP along
    the compliant axes, its other axes moved by uncoupled(), is at the TCP a wrench along the compliant
    axes alone: with the others held, the compliance block's inverse times the lead. Without the move
    the same lead pulls across too (the per-joint stiffness couples the axes)."""
    from ur3_ft_gripper_description.devices.ur_arm import force_mode as fm
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics, rotation_matrix
    arm = ArmKinematics(configured_model('ur3', True, True).text, JOINTS)
    q = np.array([0.3, -1.2, 1.4, -1.8, -1.5, 0.4])
    tcp = np.eye(4)
    tcp[2, 3] = 0.2
    jacobian = arm.jacobian(q, tcp)
    stiffness = np.array([5600.0, 5600.0, 2800.0, 1200.0, 1200.0, 1200.0])
    frame = rotation_matrix([0.2, -0.1, 0.3])
    rotation = np.kron(np.eye(2), frame)
    selection = np.array(selection) != 0
    ahead = np.where(selection, [0.001, 0.002, 0.0005, 0.0, 0.0, 0.003], 0.0)

    def pull(displacement):
        """The wrench (force frame) of the servos pulling towards `displacement` (base axes) from the TCP."""
        torques = stiffness * np.linalg.solve(jacobian, displacement)
        return rotation.T.dot(np.linalg.solve(jacobian.T, torques))

    linear, angular = fm.uncoupled(jacobian, stiffness, frame, selection, ahead)
    wrench = pull(rotation.dot(ahead) + np.concatenate((linear, angular)))
    assert np.allclose(wrench[~selection], 0.0, atol=1e-9), wrench
    compliance = rotation.T.dot(jacobian.dot(jacobian.T / stiffness[:, None])).dot(rotation)
    expected = np.linalg.solve(compliance[np.ix_(selection, selection)], ahead[selection])
    assert np.allclose(wrench[selection], expected, rtol=1e-9), (wrench, expected)
    across = pull(rotation.dot(ahead))[~selection]
    assert np.max(np.abs(across)) > 0.1 * np.max(np.abs(expected)), across


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e', 'ur10e', 'ur16e'])
def test_forward_kinematics_is_the_models_own_at_any_pose(configured_model, ur_type):
    """The control cycle's forward kinematics (its rotations made in one vectorised step) against the
    model's own chain of transforms (kinematics.Model), and the same turned by its chain product."""
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics
    model = configured_model(ur_type, True, True)
    arm = ArmKinematics(model.text, JOINTS)
    assert arm.all_revolute
    for q in np.random.default_rng(7).uniform(-2.0 * np.pi, 2.0 * np.pi, (50, 6)):
        expected = model.transform('base', 'tool0', dict(zip(JOINTS, q)))
        assert np.allclose(arm.forward(q), expected, atol=1e-12), q
        assert np.allclose(arm._chain(q)[0], expected, atol=1e-12), q


# -- Cartesian motions ----------------------------------------------------------------

HOME = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])


def test_cartesian_path_runs_along_the_line_between_its_waypoints(configured_model):
    from transforms3d.quaternions import mat2quat
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics
    from ur3_ft_gripper_description.devices.ur_arm.cartesian import PATH_STEP, Waypoint, joint_path
    arm = ArmKinematics(configured_model('ur5e', True, True).text, JOINTS)
    start = arm.forward(HOME)
    end = start[:3, 3] + [0.10, 0.0, -0.05]
    points = joint_path(arm, [Waypoint(1.0, tuple(end), tuple(mat2quat(start[:3, :3])))], HOME)
    assert len(points) == round(1.0 / PATH_STEP) and points[-1].time == pytest.approx(1.0)
    for point in points:
        # Not only the corners: every step of the path is on the line, the orientation held.
        pose = arm.forward(point.positions)
        assert np.allclose(pose[:3, 3], start[:3, 3] + point.time * (end - start[:3, 3]), atol=1e-5)
        assert np.allclose(pose[:3, :3], start[:3, :3], atol=1e-5)


@pytest.mark.parametrize('waypoints, text', [
    ([], 'no points'),
    ([(1.0, (0.3, 0.1, 0.4), (2.0, 0.0, 0.0, 0.0))], 'illegal quaternion'),
    ([(1.0, (0.3, float('nan'), 0.4), (1.0, 0.0, 0.0, 0.0))], 'NaN'),
    ([(0.0, (0.3, 0.1, 0.4), (1.0, 0.0, 0.0, 0.0))], 'strictly increasing'),
    ([(1.0, (3.0, 0.0, 0.4), (1.0, 0.0, 0.0, 0.0))], 'out of reach'),
], ids=['empty', 'quaternion', 'nan', 'time', 'reach'])
def test_cartesian_paths_the_driver_refuses_are_invalid_goal(configured_model, waypoints, text):
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics
    from ur3_ft_gripper_description.devices.ur_arm.cartesian import Waypoint, joint_path
    arm = ArmKinematics(configured_model('ur5e', True, True).text, JOINTS)
    assert_refused('INVALID_GOAL', text, lambda: joint_path(arm, [Waypoint(*w) for w in waypoints], HOME))


def test_twist_moves_the_tool_by_the_twist_and_holds_what_is_not_commanded(configured_model):
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics
    from ur3_ft_gripper_description.devices.ur_arm.cartesian import TwistFollower
    arm = ArmKinematics(configured_model('ur5e', True, True).text, JOINTS)
    follower = TwistFollower(arm)
    start = arm.forward(HOME)
    q = HOME.copy()
    for _ in range(500):  # 1 s at 500 Hz: 5 cm along y, a tenth of a radian about z
        q = follower.step(q, np.array([0.0, 0.05, 0.0, 0.0, 0.0, 0.1]), 0.002)
    pose = arm.forward(q)
    assert np.allclose(pose[:3, 3], start[:3, 3] + [0.0, 0.05, 0.0], atol=1e-6)
    expected = np.array([[np.cos(0.1), -np.sin(0.1), 0.0], [np.sin(0.1), np.cos(0.1), 0.0], [0.0, 0.0, 1.0]])
    assert np.allclose(pose[:3, :3], expected.dot(start[:3, :3]), atol=1e-6)


def test_a_urscript_pose_is_a_position_and_a_rotation_vector():
    from ur3_ft_gripper_description.devices.ur_arm.cartesian import pose_from_ur_pose
    pose = pose_from_ur_pose([0.1, -0.2, 0.3, 0.0, 0.0, math.pi / 2])
    assert np.allclose(pose[:3, 3], [0.1, -0.2, 0.3])
    assert np.allclose(pose[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-12)
    assert np.allclose(pose_from_ur_pose([0.0] * 6), np.eye(4))


def test_rotation_vector_is_the_inverse_of_rotation_matrix_up_to_half_a_turn():
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import rotation_matrix, rotation_vector
    rng = np.random.default_rng(7)
    axes = rng.normal(size=(50, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    angles = np.concatenate([[0.0, 1e-9, 1e-4, math.pi - 1e-6], rng.uniform(0.0, math.pi, 46)])
    for axis, angle in zip(axes, angles):
        rotation = rotation_matrix(axis * angle)
        assert np.allclose(rotation.dot(rotation.T), np.eye(3), atol=1e-12)
        assert np.allclose(rotation.dot(axis), axis, atol=1e-12), 'the axis is not kept'
        assert np.allclose(rotation_vector(rotation), axis * angle, atol=1e-6), (axis, angle)
    half = rotation_matrix([0.0, 0.0, math.pi])  # half a turn: either sign of the axis is right
    assert np.allclose(np.abs(rotation_vector(half)), [0.0, 0.0, math.pi], atol=1e-9)


def test_stopping_the_controller_preempts_its_goal():
    controller = jtc()
    controller.accept(7, JOINTS, [Point(2.0, [0.4] * 6)], 0.0, [0] * 6, [0] * 6)
    position, _ = run(controller, 0.5, [0] * 6)
    outcome = controller.stop(position, [0.1] * 6)
    assert (outcome.goal_id, outcome.status) == (7, 'preempted')
    stopped, outcomes = run(controller, 1.0, position)
    assert not outcomes and controller.goal is None


# -- the node's parameters: bad input is one line ------------------------------------

def settings_params(configured_model, **changes):
    params = {'~ur_type': 'ur5e', '~controller_config_file': controllers_yaml('ur5e'),
              '~controllers': ' '.join(STARTED), 'robot_description': configured_model('ur5e', True, True).text}
    params.update(changes)
    return lambda name, default=None: params.get(name, default)


def test_settings_from_the_driver_configuration(configured_model):
    from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings
    settings = read_settings(settings_params(configured_model))
    assert settings.loop_hz == 500 and settings.software.e_series and settings.joints == JOINTS
    assert settings.robot.program_running


@pytest.mark.parametrize('changes, words', [
    ({'~controller_config_file': '/nonexistent.yaml'}, ['no such file']),
    ({'~controllers': 'joint_state_controller no_such_controller'}, ['no_such_controller']),
    ({'~robot_mode': 'BACKDRIVE'}, ['~robot_mode', 'POWER_OFF, IDLE or RUNNING']),
    ({'~initial_positions': [0, 0, 0]}, ['~initial_positions', 'six']),
    ({'~initial_positions': [0, 0, 9.0, 0, 0, 0]}, ['~initial_positions', 'limits']),
    ({'robot_description': None}, ['robot_description is not set']),
    ({'~prefix': 'cell_'}, ['robot_description', "'cell_'"]),
], ids=['config', 'controller', 'mode', 'positions', 'beyond-limits', 'no-model', 'prefix'])
def test_bad_settings_are_one_line(configured_model, changes, words):
    from ur3_ft_gripper_description.devices import sim_params
    from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings
    with pytest.raises(sim_params.ParamError) as caught:
        read_settings(settings_params(configured_model, **changes))
    message = str(caught.value)
    assert '\n' not in message
    for word in words:
        assert word in message, message


def test_play_resumes_a_paused_headless_program():
    robot = new_robot(headless=True)
    assert robot.dashboard('pause') == 'Pausing program' and robot.speed_scaling() == 0.0
    assert robot.dashboard('play') == 'Starting program' and robot.speed_scaling() == 1.0
    robot.dashboard('stop')
    assert robot.dashboard('play') == 'Failed to execute: play'  # nothing loaded in headless mode


def test_joints_follow_with_the_servo_lag_within_their_limits():
    from ur3_ft_gripper_description.devices.ur_arm.joints import follow
    lower, upper, vmax = [-1.0] * 6, [1.0] * 6, [0.5] * 6
    position, velocity = follow([0.0] * 6, [0.01] + [0.0] * 5, 0.002, 0.03, vmax, lower, upper)
    assert position[0] == pytest.approx(0.01 * (1.0 - math.exp(-0.002 / 0.03)))  # first-order lag
    # Its exact solution: one late cycle of 40 ms moves the joints as five punctual ones of 8 ms do.
    late, _ = follow([0.0] * 6, [0.01] * 6, 0.04, 0.03, vmax, lower, upper)
    punctual = [0.0] * 6
    for _ in range(5):
        punctual, _ = follow(punctual, [0.01] * 6, 0.008, 0.03, vmax, lower, upper)
    assert np.allclose(late, punctual) and 0.0 < late[0] < 0.01
    position, velocity = follow([0.0] * 6, [0.9] * 6, 0.002, 0.0, vmax, lower, upper)
    assert np.allclose(velocity, 0.5)  # no faster than the limits
    position, _ = follow([0.99] * 6, [5.0] * 6, 0.1, 0.0, [100.0] * 6, lower, upper)
    assert np.allclose(position, 1.0)  # never beyond them
