#!/usr/bin/env python3
"""rostest node: the simulated arm through ur_robot_driver's documented interface (ur_driver_sim*.test).

Written from ur_robot_driver's doc/ROS_INTERFACE.md and controllers.md: the
names, types and result codes below are the documented ones; nothing here
knows how the simulation is built. ~suite: 'full' (everything) or
'trajectories' (the joint trajectory tests only, e.g. for ur3).
"""
import math
import time
import unittest

import actionlib
import numpy as np
import rospy
import rosservice
import rostest
import tf2_ros
from cartesian_control_msgs.msg import (CartesianTrajectoryPoint, FollowCartesianTrajectoryAction,
                                        FollowCartesianTrajectoryGoal, FollowCartesianTrajectoryResult)
from control_msgs.msg import (FollowJointTrajectoryAction, FollowJointTrajectoryGoal,
                              FollowJointTrajectoryResult, JointTolerance, JointTrajectoryControllerState)
from controller_manager_msgs.srv import ListControllers, SwitchController, SwitchControllerRequest
from geometry_msgs.msg import Twist, WrenchStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64, Float64MultiArray, String
from std_srvs.srv import Trigger
from tf2_msgs.msg import TFMessage
from trajectory_msgs.msg import JointTrajectoryPoint
from transforms3d.quaternions import mat2quat
from ur_dashboard_msgs.msg import RobotMode, SetModeAction, SetModeGoal
from ur_dashboard_msgs.msg import ProgramState
from ur_dashboard_msgs.srv import GetLoadedProgram, GetProgramState, GetRobotMode, Load, RawRequest
from ur_msgs.msg import IOStates
from ur_msgs.srv import GetRobotSoftwareVersion, SetIO, SetIORequest, SetSpeedSliderFraction

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices import ft300_sim, wrench_model
from ur3_ft_gripper_description.model.names import PADS
from ur3_ft_gripper_description.number_text import number_list
from ur3_ft_gripper_testing import cpu_load, rostest_helpers
from ur3_ft_gripper_testing.rostest_helpers import TIMEOUT, wait_for
from ur3_ft_gripper_testing.ur_driver import AWAY, COMMANDING, HOME, HW, JOINTS

# The default constraints' goal tolerance (config/<ur_type>_controllers.yaml: goal 0.1 rad).
GOAL_TOLERANCE = 0.1
# Universal Robots' CB3 arms; every other model runs the e-Series software (PolyScope 5).
CB3_MODELS = ('ur3', 'ur5', 'ur10')


class UrDriver(object):
    """Clients of the documented interface, made once."""

    def __init__(self):
        self.set_mode = actionlib.SimpleActionClient(HW + 'set_mode', SetModeAction)
        self.trajectory = {name: actionlib.SimpleActionClient(name + '/follow_joint_trajectory',
                                                              FollowJointTrajectoryAction)
                           for name in ('scaled_pos_joint_traj_controller', 'pos_joint_traj_controller',
                                        'scaled_vel_joint_traj_controller', 'vel_joint_traj_controller',
                                        'forward_joint_traj_controller')}
        self.cartesian = {name: actionlib.SimpleActionClient(name + '/follow_cartesian_trajectory',
                                                             FollowCartesianTrajectoryAction)
                          for name in ('pose_based_cartesian_traj_controller', 'joint_based_cartesian_traj_controller',
                                       'forward_cartesian_traj_controller')}
        for client in [self.set_mode] + list(self.trajectory.values()) + list(self.cartesian.values()):
            assert client.wait_for_server(rospy.Duration(TIMEOUT)), 'no action server %s' % client.action_client.ns
            # wait_for_server sees the server's status; a goal sent before the server subscribed
            # to the goal topic would be lost.
            wait_for(lambda: client.action_client.pub_goal.get_num_connections() > 0,
                       'the server of %s subscribes to its goals' % client.action_client.ns)
        services = dict(list_controllers=('controller_manager/list_controllers', ListControllers),
                        switch=('controller_manager/switch_controller', SwitchController),
                        set_io=(HW + 'set_io', SetIO), slider=(HW + 'set_speed_slider', SetSpeedSliderFraction),
                        resend=(HW + 'resend_robot_program', Trigger),
                        power_off=(HW + 'dashboard/power_off', Trigger), play=(HW + 'dashboard/play', Trigger),
                        get_robot_mode=(HW + 'dashboard/get_robot_mode', GetRobotMode),
                        program_state=(HW + 'dashboard/program_state', GetProgramState),
                        loaded_program=(HW + 'dashboard/get_loaded_program', GetLoadedProgram),
                        load_program=(HW + 'dashboard/load_program', Load),
                        raw_request=(HW + 'dashboard/raw_request', RawRequest),
                        pause=(HW + 'dashboard/pause', Trigger),
                        version=(HW + 'get_robot_software_version', GetRobotSoftwareVersion),
                        zero_ftsensor=(HW + 'zero_ftsensor', Trigger))
        for key, (name, kind) in services.items():
            rospy.wait_for_service(name, TIMEOUT)
            setattr(self, key, rospy.ServiceProxy(name, kind))
        self.script = rospy.Publisher(HW + 'script_command', String, queue_size=1)
        self.twist = rospy.Publisher('twist_controller/command', Twist, queue_size=1)
        self.velocity = rospy.Publisher('joint_group_vel_controller/command', Float64MultiArray, queue_size=1)

    def controller_states(self):
        return {c.name: c.state for c in self.list_controllers().controller}

    def only(self, controller):
        """Make `controller` the one commanding controller, as ur_robot_driver's integration test switches."""
        request = SwitchControllerRequest(start_controllers=[controller],
                                          stop_controllers=[c for c in COMMANDING if c != controller],
                                          strictness=SwitchControllerRequest.BEST_EFFORT)
        assert self.switch(request).ok
        assert self.controller_states()[controller] == 'running'


def joint_goal(names, points):
    """A goal for the joints `names` (unprefixed: the model's ~prefix is put in front)."""
    prefix = rospy.get_param('~prefix', '')
    goal = FollowJointTrajectoryGoal()
    goal.trajectory.joint_names = [prefix + name for name in names]
    for seconds, positions in points:
        goal.trajectory.points.append(JointTrajectoryPoint(positions=list(positions),
                                                           time_from_start=rospy.Duration(seconds)))
    return goal


def arm_positions(prefix=''):
    names = [prefix + j for j in JOINTS]

    def arm_message():
        msg = rospy.wait_for_message('joint_states', JointState, TIMEOUT)
        return msg if set(msg.name) == set(names) else None
    msg = wait_for(arm_message, 'an arm message on joint_states')
    return np.array([msg.position[msg.name.index(n)] for n in names]), msg


class DriverTestBase(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.driver = UrDriver()
        cls.prefix = rospy.get_param('~prefix', '')
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)

    def setUp(self):
        # Every test starts from a running robot with its program running.
        goal = SetModeGoal(target_robot_mode=RobotMode(mode=RobotMode.RUNNING), play_program=True)
        self.driver.set_mode.send_goal(goal)
        rostest_helpers.wait_for_result(self.driver.set_mode)
        self.assertTrue(self.driver.set_mode.get_result().success, self.driver.set_mode.get_result().message)
        self.assertTrue(self.driver.slider(1.0).success)
        self.driver.only('scaled_pos_joint_traj_controller')

    def run_goal(self, goal, controller='scaled_pos_joint_traj_controller', timeout=TIMEOUT):
        client = self.driver.trajectory.get(controller) or self.driver.cartesian[controller]
        client.send_goal(goal)
        rostest_helpers.wait_for_result(client, timeout)
        return client.get_state(), client.get_result()

    def move_to(self, positions, seconds=2.0, controller='scaled_pos_joint_traj_controller'):
        state, result = self.run_goal(joint_goal(JOINTS, [(seconds, positions)]), controller)
        self.assertEqual(result.error_code, FollowJointTrajectoryResult.SUCCESSFUL, result.error_string)

    def assert_at(self, positions, tolerance=GOAL_TOLERANCE):
        actual, _ = arm_positions(self.prefix)
        np.testing.assert_allclose(actual, positions, atol=tolerance)

    def tool(self, frame='tool0_controller'):
        return rostest_helpers.lookup(self.buffer, self.prefix + 'base', self.prefix + frame)


class JointTrajectoryTest(DriverTestBase):
    """The scaled and unscaled position controllers (run for every ur_type)."""

    def test_scaled_trajectory_succeeds_in_any_joint_order(self):
        # As ur_robot_driver's integration test orders them: elbow first.
        names = ['elbow_joint', 'shoulder_lift_joint', 'shoulder_pan_joint', 'wrist_1_joint', 'wrist_2_joint',
                 'wrist_3_joint']
        order = [JOINTS.index(n) for n in names]
        points = [(1.0, [HOME[i] for i in order]), (2.5, [AWAY[i] for i in order]), (4.0, [HOME[i] for i in order])]
        state, result = self.run_goal(joint_goal(names, points))
        self.assertEqual(result.error_code, FollowJointTrajectoryResult.SUCCESSFUL, result.error_string)
        self.assertEqual(state, actionlib.GoalStatus.SUCCEEDED)
        self.assert_at(HOME)

    def test_goal_time_tolerance_fails_an_arrival_the_robot_cannot_make(self):
        # As ur_robot_driver's integration test: a fast last segment, first without a goal time
        # (the config's goal_time applies: success), then with 0.01 s, which the robot's servo cannot
        # settle within (GOAL_TOLERANCE_VIOLATED).
        self.move_to(HOME)
        goal = joint_goal(JOINTS, [(1.0, HOME), (1.5, AWAY)])
        state, result = self.run_goal(goal)
        self.assertEqual(result.error_code, FollowJointTrajectoryResult.SUCCESSFUL, result.error_string)
        goal = joint_goal(JOINTS, [(1.0, AWAY), (1.5, HOME)])
        goal.goal_time_tolerance = rospy.Duration(0.01)
        state, result = self.run_goal(goal)
        self.assertEqual(result.error_code, FollowJointTrajectoryResult.GOAL_TOLERANCE_VIOLATED)
        self.assertEqual(state, actionlib.GoalStatus.ABORTED)

    def test_unscaled_controller_succeeds(self):
        self.driver.only('pos_joint_traj_controller')
        self.move_to(AWAY, controller='pos_joint_traj_controller')
        self.assert_at(AWAY)

    def test_illegal_joint_name_is_invalid_joints(self):
        names = JOINTS[:5] + ['wrist_4_joint']
        state, result = self.run_goal(joint_goal(names, [(2.0, HOME)]))
        self.assertEqual(result.error_code, FollowJointTrajectoryResult.INVALID_JOINTS)
        self.assertEqual(state, actionlib.GoalStatus.REJECTED)

    def test_an_extra_unknown_joint_beside_the_six_is_invalid_joints(self):
        state, result = self.run_goal(joint_goal(JOINTS + ['wrist_4_joint'], [(2.0, HOME + [0.0])]))
        self.assertEqual(result.error_code, FollowJointTrajectoryResult.INVALID_JOINTS)
        self.assertEqual(state, actionlib.GoalStatus.REJECTED)

    def test_a_goal_ending_at_rest_off_its_target_violates_the_goal_tolerance(self):
        # controllers.md: the unscaled controllers do not respect a paused program. Here the
        # trajectory runs on while the paused robot stands still; without a path tolerance the
        # goal ends with the arm at rest, far from the last point.
        self.move_to(HOME)
        self.driver.only('pos_joint_traj_controller')
        self.assertTrue(self.driver.pause().success)
        time.sleep(0.2)
        held, _ = arm_positions(self.prefix)
        goal = joint_goal(JOINTS, [(0.5, AWAY)])
        goal.path_tolerance = [JointTolerance(name=self.prefix + j, position=-1.0) for j in JOINTS]
        state, result = self.run_goal(goal, 'pos_joint_traj_controller')
        self.assertEqual(result.error_code, FollowJointTrajectoryResult.GOAL_TOLERANCE_VIOLATED, result.error_string)
        self.assertEqual(state, actionlib.GoalStatus.ABORTED)
        self.assert_at(held, 1e-9)

    def test_bad_trajectories_are_invalid_goal(self):
        beyond = list(HOME)
        beyond[0] = 7.0  # the model's limits are +-2 pi
        for what, points in (('non-increasing times', [(6.0, HOME), (3.0, AWAY)]),
                             ('NaN position', [(2.0, [float('nan')] + HOME[1:])]),
                             ('beyond the joint limits', [(2.0, beyond)])):
            state, result = self.run_goal(joint_goal(JOINTS, points))
            self.assertEqual(result.error_code, FollowJointTrajectoryResult.INVALID_GOAL, what)
            self.assertEqual(state, actionlib.GoalStatus.REJECTED, what)
            self.assertTrue(result.error_string, what)

    def test_speed_slider_slows_the_scaled_trajectory(self):
        self.move_to(HOME)
        self.assertTrue(self.driver.slider(0.5).success)
        self.assertFalse(self.driver.slider(1.5).success)
        wait_for(lambda: abs(rospy.wait_for_message('speed_scaling_factor', Float64, TIMEOUT).data - 0.5) < 1e-6,
                   'speed_scaling_factor 0.5')
        start = time.monotonic()
        self.move_to(AWAY, seconds=1.0)
        self.assertGreater(time.monotonic() - start, 1.8)  # half speed: twice the time (and then some)

    def test_over_fast_trajectory_is_slowed_to_the_joint_velocity_limits(self):
        self.move_to(HOME)
        far = list(HOME)
        far[0] = HOME[0] + 3.0  # 3 rad in 0.2 s: far above any UR joint's velocity limit
        recorder = rostest_helpers.Recorder('joint_states', JointState)
        start = time.monotonic()
        self.move_to(far, seconds=0.2)
        limit = rospy.get_param('robot_description')
        model = kinematics.Model(limit)
        vmax = model.joints[self.prefix + 'shoulder_pan_joint'].limit.velocity
        speeds = [abs(m.velocity[m.name.index(self.prefix + 'shoulder_pan_joint')])
                  for m in recorder.since(start) if self.prefix + 'shoulder_pan_joint' in m.name]
        self.assertTrue(speeds)
        self.assertLessEqual(max(speeds), vmax * 1.001)
        self.assertGreater(time.monotonic() - start, 3.0 / vmax)
        self.assert_at(far)

    def test_new_goal_preempts_and_cancel_stops(self):
        self.move_to(HOME)
        client = self.driver.trajectory['scaled_pos_joint_traj_controller']
        client.send_goal(joint_goal(JOINTS, [(4.0, AWAY)]))
        time.sleep(1.0)
        second = actionlib.SimpleActionClient('scaled_pos_joint_traj_controller/follow_joint_trajectory',
                                              FollowJointTrajectoryAction)
        second.wait_for_server(rospy.Duration(TIMEOUT))
        second.send_goal(joint_goal(JOINTS, [(4.0, HOME)]))
        rostest_helpers.wait_for_result(client)
        self.assertEqual(client.get_state(), actionlib.GoalStatus.PREEMPTED)
        time.sleep(0.5)
        second.cancel_goal()
        rostest_helpers.wait_for_result(second)
        self.assertEqual(second.get_state(), actionlib.GoalStatus.PREEMPTED)
        # On ROS time (simulated on the physics cell, which a loaded machine slows): stop_trajectory_duration
        # is 0.5 s, and the servos then hold the arm within microradians (1.2 urad moved in a half second
        # of the wall clock once, the cell running slower than it under load).
        rospy.sleep(1.0)
        before, _ = arm_positions(self.prefix)
        rospy.sleep(0.5)
        after, _ = arm_positions(self.prefix)
        np.testing.assert_allclose(after, before, atol=1e-5)

    def test_state_topic_reports_desired_and_actual(self):
        msg = rospy.wait_for_message('scaled_pos_joint_traj_controller/state', JointTrajectoryControllerState,
                                     TIMEOUT)
        self.assertEqual(list(msg.joint_names), [self.prefix + j for j in JOINTS])
        self.assertEqual(len(msg.actual.positions), 6)


class RobotTest(DriverTestBase):
    """Modes, program, IO, script, controllers, state (the full suite)."""

    def test_power_off_refuses_commands_and_set_mode_brings_it_back(self):
        self.assertEqual(self.driver.power_off().message, 'Powering off')
        wait_for(lambda: not rospy.wait_for_message(HW + 'robot_program_running', Bool, TIMEOUT).data,
                   'robot_program_running false')
        mode = rospy.wait_for_message(HW + 'robot_mode', RobotMode, TIMEOUT)
        self.assertEqual(mode.mode, RobotMode.POWER_OFF)
        state, result = self.run_goal(joint_goal(JOINTS, [(2.0, HOME)]))
        self.assertEqual(state, actionlib.GoalStatus.REJECTED)
        self.assertEqual(result.error_code, FollowJointTrajectoryResult.INVALID_GOAL)
        self.assertEqual(self.driver.play().success, False)
        goal = SetModeGoal(target_robot_mode=RobotMode(mode=RobotMode.RUNNING), play_program=True)
        self.driver.set_mode.send_goal(goal)
        rostest_helpers.wait_for_result(self.driver.set_mode)
        self.assertTrue(self.driver.set_mode.get_result().success)
        self.assertEqual(self.driver.get_robot_mode().robot_mode.mode, RobotMode.RUNNING)
        self.assertTrue(rospy.wait_for_message(HW + 'robot_program_running', Bool, TIMEOUT).data)
        wait_for(lambda: self.driver.controller_states()['scaled_pos_joint_traj_controller'] == 'running',
                   'the controller_stopper starts the controller again')
        self.move_to(HOME)

    def test_switch_controllers_strict_and_best_effort(self):
        states = self.driver.controller_states()
        for name in COMMANDING:
            self.assertIn(name, states)
        strict = SwitchControllerRequest.STRICT
        unknown = SwitchControllerRequest(start_controllers=['no_such_controller'],
                                          stop_controllers=['scaled_pos_joint_traj_controller'], strictness=strict)
        self.assertFalse(self.driver.switch(unknown).ok)
        self.assertEqual(self.driver.controller_states(), states)
        # Two commanding controllers never run together.
        both = SwitchControllerRequest(start_controllers=['pos_joint_traj_controller'], strictness=strict)
        self.assertFalse(self.driver.switch(both).ok)
        swap = SwitchControllerRequest(start_controllers=['pos_joint_traj_controller'],
                                       stop_controllers=['scaled_pos_joint_traj_controller'], strictness=strict)
        self.assertTrue(self.driver.switch(swap).ok)
        states = self.driver.controller_states()
        self.assertEqual(states['pos_joint_traj_controller'], 'running')
        self.assertEqual(states['scaled_pos_joint_traj_controller'], 'stopped')
        state, result = self.run_goal(joint_goal(JOINTS, [(2.0, HOME)]))
        self.assertEqual(result.error_code, FollowJointTrajectoryResult.INVALID_GOAL)  # stopped: refused
        best = SwitchControllerRequest(start_controllers=['scaled_pos_joint_traj_controller', 'no_such_controller'],
                                       stop_controllers=['pos_joint_traj_controller', 'twist_controller'],
                                       strictness=SwitchControllerRequest.BEST_EFFORT)
        self.assertTrue(self.driver.switch(best).ok)
        self.assertEqual(self.driver.controller_states()['scaled_pos_joint_traj_controller'], 'running')

    def test_every_joint_trajectory_controller_succeeds(self):
        for controller in ('scaled_vel_joint_traj_controller', 'vel_joint_traj_controller',
                           'forward_joint_traj_controller', 'scaled_pos_joint_traj_controller'):
            self.driver.only(controller)
            self.move_to(AWAY if controller != 'scaled_pos_joint_traj_controller' else HOME, seconds=1.5,
                         controller=controller)

    def test_dashboard_program_and_pause(self):
        self.assertEqual(self.driver.program_state().state.state, ProgramState.PLAYING)
        self.assertFalse(self.driver.load_program('no_such_program.urp').success)
        self.assertTrue(self.driver.loaded_program().success is not None)
        self.assertEqual(self.driver.raw_request('robotmode').answer, 'Robotmode: RUNNING')
        # A paused program holds the scaled trajectory: speed scaling 0 until play.
        self.move_to(HOME)
        client = self.driver.trajectory['scaled_pos_joint_traj_controller']
        client.send_goal(joint_goal(JOINTS, [(1.5, AWAY)]))
        time.sleep(0.5)
        self.assertTrue(self.driver.pause().success)
        wait_for(lambda: rospy.wait_for_message('speed_scaling_factor', Float64, TIMEOUT).data == 0.0,
                   'speed_scaling_factor 0 while paused')
        time.sleep(0.3)  # the joints settle on the held command (servoj's lookahead time, 0.03 s)
        held, _ = arm_positions(self.prefix)
        time.sleep(1.5)
        np.testing.assert_allclose(arm_positions(self.prefix)[0], held, atol=1e-6)
        self.assertEqual(client.get_state(), actionlib.GoalStatus.ACTIVE)
        self.assertTrue(self.driver.play().success)
        rostest_helpers.wait_for_result(client)
        self.assertEqual(client.get_result().error_code, FollowJointTrajectoryResult.SUCCESSFUL)
        self.assert_at(AWAY)

    def test_read_only_controllers_publish_while_they_run(self):
        stop = SwitchControllerRequest(stop_controllers=['force_torque_sensor_controller'],
                                       strictness=SwitchControllerRequest.STRICT)
        self.assertTrue(self.driver.switch(stop).ok)
        time.sleep(0.2)
        with self.assertRaises(rospy.ROSException):
            rospy.wait_for_message('wrench', WrenchStamped, 1.0)
        start = SwitchControllerRequest(start_controllers=['force_torque_sensor_controller'],
                                        strictness=SwitchControllerRequest.STRICT)
        self.assertTrue(self.driver.switch(start).ok)
        rospy.wait_for_message('wrench', WrenchStamped, TIMEOUT)

    def test_set_io_shows_in_io_states(self):
        for state in (1.0, 0.0):
            response = self.driver.set_io(SetIORequest(fun=SetIORequest.FUN_SET_DIGITAL_OUT,
                                                       pin=SetIORequest.PIN_DOUT3, state=state))
            self.assertTrue(response.success)
            wait_for(lambda: rospy.wait_for_message(HW + 'io_states', IOStates, TIMEOUT)
                       .digital_out_states[3].state == bool(state), 'digital out 3 = %g' % state)
        self.assertFalse(self.driver.set_io(SetIORequest(fun=SetIORequest.FUN_SET_DIGITAL_OUT, pin=40,
                                                         state=1.0)).success)

    def test_script_outputs_show_on_io_states_by_their_pin_numbers(self):
        rostest_helpers.wait_for_subscribers(self.driver.script)

        def outputs_on():
            msg = rospy.wait_for_message(HW + 'io_states', IOStates, TIMEOUT)
            return [d.pin for d in msg.digital_out_states if d.state]
        for on, expected in ((True, [10, 17]), (False, [])):
            # A secondary program runs beside External Control. io_states numbers the
            # outputs 0-7 standard, 8-15 configurable, 16-17 tool.
            self.driver.script.publish(String(data='sec io():\n  set_configurable_digital_out(2, %s)\n'
                                                   '  set_tool_digital_out(1, %s)\nend' % (on, on)))
            wait_for(lambda: outputs_on() == expected, lambda: 'digital outputs %s on (are: %s)' % (
                expected, outputs_on()))
        self.assertTrue(rospy.wait_for_message(HW + 'robot_program_running', Bool, TIMEOUT).data)

    def test_movej_without_a_and_v_takes_the_manuals_default_profile(self):
        # URScript manual: movej(q, a=1.4, v=1.05, ...). 1 rad on the leading joint is more than
        # the ramps' v^2/a: accelerate, cruise at v, decelerate, 1/v + v/a = 1.70 s in all, no less.
        self.move_to(HOME)
        time.sleep(0.3)  # the joints settle (servoj's lookahead time)
        target = list(HOME)
        target[0] += 1.0
        recorder = rostest_helpers.Recorder('joint_states', JointState)
        rostest_helpers.wait_for_subscribers(self.driver.script)
        self.driver.script.publish(String(data='movej([%s])' % number_list(target)))
        pan = self.prefix + 'shoulder_pan_joint'

        def samples_to_the_target():
            # Judged on this recorder's own states: another subscriber's may hear the arrival first.
            samples = [(m.header.stamp.to_sec(), m.position[m.name.index(pan)]) for m in recorder.since(0.0)
                       if pan in m.name]
            return samples if any(abs(p - target[0]) < 1e-9 for _, p in samples) else None
        samples = wait_for(samples_to_the_target, 'movej reaches its target on joint_states')
        # The first state that moved, taken back to where the motion began along the manual's ramp
        # (a = 1.4 rad/s^2): a loaded machine may drop the first states of the motion before this
        # process reads them, and a later first state alone would shorten the motion by what was lost.
        moved_at, moved = next((t, abs(p - HOME[0])) for t, p in samples if abs(p - HOME[0]) > 1e-9)
        started = moved_at - math.sqrt(2.0 * moved / 1.4)
        arrived = next(t for t, p in samples if abs(p - target[0]) < 1e-9)
        # The robot's clock runs with the node's: a late cycle can only make the motion longer.
        self.assertGreater(arrived - started, 1.0 / 1.05 + 1.05 / 1.4 - 0.05)
        # Not slower than the manual's profile either: it cruises at v = 1.05 rad/s. Judged on the speed
        # over 0.1 s of the cycles the node ran, not on the whole motion's length: on the wall clock a stall
        # of the machine longer than the node makes up (ten periods) is lost time, which lengthens the
        # motion without making any stretch of it faster, and leaves a gap in the stamps the joints did not
        # move through. A state's stamp is the time its cycle integrated to, so a stall between the cycle
        # and its publication does not compress the stamps; servoj's lookahead filter leaves the joint
        # within 0.005 rad/s of v by the cruise's second half.
        gaps = sorted(b[0] - a[0] for a, b in zip(samples, samples[1:]))
        period = gaps[len(gaps) // 2]
        # The cycles that ran: a cycle's step is at most one and a half periods (sim_clock.wall_cycles).
        ran = [(t1 - t0, p1 - p0) for (t0, p0), (t1, p1) in zip(samples, samples[1:])
               if t1 - t0 <= 1.5 * period + 1e-6]
        speeds = []
        for i in range(len(ran)):
            took = moved = 0.0
            for dt, dp in ran[i:]:
                took, moved = took + dt, moved + dp
                if took >= 0.1:
                    speeds.append(moved / took)
                    break
        self.assertAlmostEqual(max(speeds), 1.05, delta=0.03, msg='the cruise speed of movej (rad/s)')

    def test_a_program_through_script_command_then_resend_robot_program(self):
        # A program as users send one: a straight tool move up, then a joint move. It replaces External
        # Control; resend_robot_program (headless mode) brings it back and the controller runs again.
        self.move_to(HOME)
        rostest_helpers.wait_for_subscribers(self.driver.script)
        self.driver.script.publish(String(data='def up_and_away():\n'
                                          '  movel(pose_add(get_actual_tcp_pose(), p[0, 0, 0.03, 0, 0, 0]), '
                                          'a=0.5, v=0.1)\n'
                                          '  movej([%s], a=1.4, v=1.05)\n'
                                          'end\n' % number_list(AWAY)))
        wait_for(lambda: not rospy.wait_for_message(HW + 'robot_program_running', Bool, TIMEOUT).data,
                   'the script replaces the External Control program')
        wait_for(lambda: np.allclose(arm_positions(self.prefix)[0], AWAY, atol=1e-3), 'movej reaches its target')
        self.assertEqual(self.driver.controller_states()['scaled_pos_joint_traj_controller'], 'stopped')
        response = self.driver.resend()
        self.assertTrue(response.success, response.message)
        wait_for(lambda: rospy.wait_for_message(HW + 'robot_program_running', Bool, TIMEOUT).data,
                   'robot_program_running after resend_robot_program')
        wait_for(lambda: self.driver.controller_states()['scaled_pos_joint_traj_controller'] == 'running',
                   'the controller runs again')
        self.move_to(HOME)

    def test_state_topics(self):
        version = self.driver.version()
        self.assertGreaterEqual(version.major, 3)
        msg = rospy.wait_for_message('speed_scaling_factor', Float64, TIMEOUT)
        self.assertAlmostEqual(msg.data, 1.0)
        wrench = rospy.wait_for_message('wrench', WrenchStamped, TIMEOUT)
        self.assertEqual(wrench.header.frame_id, self.prefix + 'tool0_controller')
        # tool0_controller is the robot's own tool0: the same pose as the model's. The two
        # latest poses may be a cycle apart while the joints settle, so wait for them to agree.
        wait_for(lambda: np.allclose(self.tool('tool0_controller'), self.tool('tool0'), atol=1e-4),
                 lambda: 'tool0_controller at the model\'s tool0 (last: %s vs %s)' % (
                     self.tool('tool0_controller')[:3, 3], self.tool('tool0')[:3, 3]))

    def cartesian_goal(self, target, seconds=2.0):
        goal = FollowCartesianTrajectoryGoal()
        point = CartesianTrajectoryPoint(time_from_start=rospy.Duration(seconds))
        point.pose.position.x, point.pose.position.y, point.pose.position.z = target[:3, 3]
        w, x, y, z = mat2quat(target[:3, :3])
        point.pose.orientation.w, point.pose.orientation.x = w, x
        point.pose.orientation.y, point.pose.orientation.z = y, z
        goal.trajectory.points.append(point)
        return goal

    def test_cartesian_controllers_reach_their_targets(self):
        for index, controller in enumerate(('pose_based_cartesian_traj_controller',
                                            'joint_based_cartesian_traj_controller',
                                            'forward_cartesian_traj_controller')):
            self.move_to(HOME)
            self.driver.only(controller)
            start = self.tool()
            target = start.copy()
            target[:3, 3] += [0.05, -0.03, 0.04 if index % 2 == 0 else -0.04]
            state, result = self.run_goal(self.cartesian_goal(target), controller)
            self.assertEqual(result.error_code, FollowCartesianTrajectoryResult.SUCCESSFUL, result.error_string)
            time.sleep(0.2)
            np.testing.assert_allclose(self.tool(), target, atol=2e-3, err_msg=controller)
            self.driver.only('scaled_pos_joint_traj_controller')

    def test_cartesian_goal_out_of_reach_is_invalid_goal(self):
        self.driver.only('pose_based_cartesian_traj_controller')
        target = np.eye(4)
        target[:3, 3] = [5.0, 0.0, 0.5]
        state, result = self.run_goal(self.cartesian_goal(target), 'pose_based_cartesian_traj_controller')
        self.assertEqual(result.error_code, FollowCartesianTrajectoryResult.INVALID_GOAL)

    def test_twist_and_joint_group_velocity(self):
        self.move_to(HOME)
        self.driver.only('twist_controller')
        start = self.tool()
        rostest_helpers.wait_for_subscribers(self.driver.twist)
        twist = Twist()
        twist.linear.z = 0.05
        twist.angular.z = 0.2
        model = kinematics.Model(rospy.get_param('robot_description'))
        base, tool0 = self.prefix + 'base', self.prefix + 'tool0'
        recorder = rostest_helpers.Recorder('joint_states', JointState)
        began = rospy.get_time()
        hold_command(self.driver.twist, twist, Twist(), 1.0)
        ended = rospy.get_time()
        time.sleep(0.3)
        end = self.tool()
        # The speeds as the robot's own joint states show them (their stamps): the median over consecutive
        # states of the middle of the hold. On a loaded machine the kinematic arm drops the time of a cycle
        # it ran very late, as a real controller would not: one pair of states, not the median.
        states = [m for m in recorder.since(0.0) if self.prefix + 'shoulder_pan_joint' in m.name and
                  began + 0.2 <= m.header.stamp.to_sec() <= ended - 0.1]
        poses = [(m.header.stamp.to_sec(), model.transform(base, tool0, dict(zip(m.name, m.position))))
                 for m in states]
        self.assertGreater(len(poses), 20, 'joint states in the middle of the hold')
        rise = median_rate([(t, pose[2, 3]) for t, pose in poses])
        yaw = median_rate([(t, math.atan2(pose[:3, :3].dot(poses[0][1][:3, :3].T)[1, 0],
                                          pose[:3, :3].dot(poses[0][1][:3, :3].T)[0, 0])) for t, pose in poses])
        self.assertAlmostEqual(rise, 0.05, delta=0.0025)
        self.assertAlmostEqual(yaw, 0.2, delta=0.01)
        moved = end[:3, 3] - start[:3, 3]
        # Up, and nothing but up, however long the twist was held.
        self.assertGreater(moved[2], 0.02)
        self.assertLess(np.linalg.norm(moved[:2]), 0.1 * moved[2])
        # speedl turns the tool about the base's z axis through the tool's own origin.
        turn = end[:3, :3].dot(start[:3, :3].T)
        np.testing.assert_allclose(turn[:, 2], [0.0, 0.0, 1.0], atol=1e-3)
        self.driver.only('joint_group_vel_controller')
        rostest_helpers.wait_for_subscribers(self.driver.velocity)
        began = rospy.get_time()
        hold_command(self.driver.velocity, Float64MultiArray(data=[0.1, 0, 0, 0, 0, 0]),
                     Float64MultiArray(data=[0.0] * 6), 1.0)
        ended = rospy.get_time()
        pan = [(m.header.stamp.to_sec(), m.position[m.name.index(self.prefix + 'shoulder_pan_joint')])
               for m in recorder.since(0.0) if self.prefix + 'shoulder_pan_joint' in m.name and
               began + 0.2 <= m.header.stamp.to_sec() <= ended - 0.1]
        self.assertGreater(len(pan), 20, 'joint states in the middle of the hold')
        self.assertAlmostEqual(median_rate(pan), 0.1, delta=0.005)


def median_rate(samples):
    """The median rate of change of [(time, value)] between consecutive samples."""
    rates = sorted((b - a) / (tb - ta) for (ta, a), (tb, b) in zip(samples, samples[1:]) if tb > ta)
    return rates[len(rates) // 2]


def hold_command(publisher, command, release, seconds):
    """Publish `command` at 50 Hz for `seconds` (wall clock), then `release`."""
    start = time.monotonic()
    while time.monotonic() - start < seconds:
        publisher.publish(command)
        time.sleep(0.02)
    publisher.publish(release)


class GenerationTest(DriverTestBase):
    """What depends on the controller generation of ~ur_type: CB3 or e-Series software."""

    def test_software_version_and_zero_ftsensor_follow_the_generation(self):
        cb3 = rospy.get_param('~ur_type') in CB3_MODELS
        version = self.driver.version()
        self.assertEqual(version.major < 5, cb3, version)
        response = self.driver.zero_ftsensor()
        # ur_robot_driver: "only available for e-Series robots (Major version >= 5)".
        self.assertEqual(response.success, not cb3, response.message)
        remote = HW + 'dashboard/is_in_remote_control' in rosservice.get_service_list()
        self.assertEqual(remote, not cb3)  # ROS_INTERFACE.md: "only available on e-Series models"


class ModelAlongTrajectoryTest(DriverTestBase):
    """TF of tool0 and the finger pads, and the FT 300's wrench, while the scaled controller moves the arm."""

    def test_tf_and_wrench_follow_the_trajectory(self):
        self.move_to(HOME)
        model = kinematics.Model(rospy.get_param('robot_description'))
        finger = {}

        def finger_message():
            msg = rospy.wait_for_message('joint_states', JointState, TIMEOUT)
            if self.prefix + 'finger_joint' in msg.name:
                finger.update(zip(msg.name, msg.position))
            return finger
        wait_for(finger_message, 'finger_joint on joint_states')
        # robot_state_publisher turns some joint_states messages into TF (at its publish_frequency)
        # and tf2 interpolates between them: compare at the stamps of its own arm transforms,
        # with the joint_states message of each such stamp, after the motion (TF keeps 10 s).
        tf_stamps = set()
        last_link = self.prefix + 'wrist_3_link'

        def on_tf(msg):
            tf_stamps.update(t.header.stamp for t in msg.transforms if t.child_frame_id == last_link)
        tf_sub = rospy.Subscriber('/tf', TFMessage, on_tf, queue_size=1000)
        recorder = rostest_helpers.Recorder('joint_states', JointState)
        client = self.driver.trajectory['scaled_pos_joint_traj_controller']
        start = time.monotonic()
        client.send_goal(joint_goal(JOINTS, [(3.0, AWAY)]))
        rostest_helpers.wait_for_result(client)
        self.assertEqual(client.get_result().error_code, FollowJointTrajectoryResult.SUCCESSFUL)
        time.sleep(0.5)
        tf_sub.unregister()
        samples = [m for m in recorder.since(start) if self.prefix + 'shoulder_pan_joint' in m.name and
                   m.header.stamp in tf_stamps]
        fractions_seen = []
        for sample in samples[::max(1, len(samples) // 20)]:
            positions = dict(finger, **dict(zip(sample.name, sample.position)))
            # One point with positions only: a straight line in joint space from HOME to AWAY.
            arm = np.array([positions[self.prefix + j] for j in JOINTS])
            fractions = (arm - HOME) / (np.array(AWAY) - HOME)
            np.testing.assert_allclose(fractions, fractions[0], atol=1e-6, err_msg='off the trajectory')
            fractions_seen.append(fractions[0])
            for frame in ['tool0'] + list(PADS):
                msg = self.buffer.lookup_transform(self.prefix + 'base_link', self.prefix + frame,
                                                   sample.header.stamp, rospy.Duration(1.0))
                expected = model.transform(self.prefix + 'base_link', self.prefix + frame, positions)
                np.testing.assert_allclose(rostest_helpers.transform_matrix(msg.transform), expected, atol=1e-6,
                                           err_msg='%s at %s' % (frame, sample.position))
        # Checked along the way, not only at the ends.
        self.assertGreaterEqual(len([f for f in fractions_seen if 0.05 < f < 0.95]), 5, fractions_seen)
        # The FT 300 reads the gripper's weight in its own frame: it turns with the sensor.
        gripper = wrench_model.Load(*ft300_sim.tool_side_load(rospy.get_param('robot_description'),
                                                              self.prefix + 'robotiq_ft_frame_id'))
        readings = []
        for pose in (HOME, AWAY):
            self.move_to(pose)
            time.sleep(0.3)
            sensor = rostest_helpers.lookup(self.buffer, self.prefix + 'base_link',
                                            self.prefix + 'robotiq_ft_frame_id')
            gravity = sensor[:3, :3].T.dot([0.0, 0.0, -1.0])
            expected = wrench_model.gravity_wrench(gravity[0], gravity[1], gravity[2], gripper.mass, gripper.com)
            msgs = [rospy.wait_for_message('robotiq_ft_wrench', WrenchStamped, TIMEOUT) for _ in range(20)]
            force = np.mean([[m.wrench.force.x, m.wrench.force.y, m.wrench.force.z] for m in msgs], axis=0)
            np.testing.assert_allclose(force - rostest_helpers.FT300_UNIT_OFFSET[:3], expected[:3], atol=0.15)
            readings.append(force)
        self.assertGreater(np.linalg.norm(readings[0] - readings[1]), 1.0)


class FullSuite(JointTrajectoryTest, RobotTest, GenerationTest, ModelAlongTrajectoryTest):
    """Every part of the interface (rostest.rosrun takes one TestCase class)."""


class TrajectorySuite(JointTrajectoryTest, GenerationTest):
    """The joint trajectory tests, and the generation's."""


if __name__ == '__main__':
    rospy.init_node('ur_driver_sim_check')
    suite = rospy.get_param('~suite', 'full')
    # ~cpu_load: one busy process per core beside the cell while the tests run, as on a shared CI runner.
    with cpu_load.CpuLoad() if rospy.get_param('~cpu_load', False) else cpu_load.NoLoad():
        rostest.rosrun('ur3_ft_gripper_description', 'ur_driver_sim_' + suite,
                       TrajectorySuite if suite == 'trajectories' else FullSuite)
