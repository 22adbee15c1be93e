"""Simulated UR controller behind ur_robot_driver's ROS interface (node ur_hardware_interface).

What a user's code and launch files talk to on the real cell, under the
same names and types (ur_robot_driver 2.4.1's ROS_INTERFACE.md and
controllers.md), so that they run unchanged with sim:=true:
- state: joint_states (joint_state_controller) at the config's loop_hz, the
  `tool0_controller` TF frame, speed_scaling_factor, wrench (the robot's own
  TCP sensor, in tool0_controller), ~io_states, ~tool_data, ~robot_program_running,
  ~robot_mode, ~safety_mode;
- ~set_mode (robot_state_helper's action), ~dashboard/*, ~resend_robot_program,
  ~hand_back_control, ~set_speed_slider, ~set_io, ~set_analog_output, ~set_payload,
  ~zero_ftsensor, ~get_robot_software_version, ~activate_spline_interpolation,
  ~script_command;
- controller_manager/list_controllers, switch_controller (and the other
  controller_manager services) over the controllers of ur_robot_driver's
  config/<ur_type>_controllers.yaml;
- every trajectory controller's follow_joint_trajectory action, and
  joint_trajectory_controller's command, state and query_state (not the
  pass-through controllers', which have only their action); joint_group_vel_controller/command;
  twist_controller/command; the Cartesian controllers' follow_cartesian_trajectory.

The controller_stopper of ur_control.launch is built in: when the program
stops, the commanding controllers stop, and they start again when it runs.

The arm is kinematic: the joints go where they are commanded, no faster
than the model's velocity limits; there are no dynamics, no collisions and
no protective stops.
"""

import math
import threading

import actionlib
import numpy as np
import tf2_ros
from cartesian_control_msgs.msg import FollowCartesianTrajectoryAction, FollowCartesianTrajectoryResult
from control_msgs.msg import FollowJointTrajectoryAction, FollowJointTrajectoryResult, JointTrajectoryControllerState
from control_msgs.srv import QueryTrajectoryState
from controller_manager_msgs import srv as cm_srv
from controller_manager_msgs.msg import ControllerState, HardwareInterfaceResources
from geometry_msgs.msg import TransformStamped, Twist, WrenchStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64, Float64MultiArray, String
from std_srvs.srv import SetBool, Trigger
from trajectory_msgs.msg import JointTrajectory
from transforms3d.quaternions import mat2quat
from ur_dashboard_msgs.msg import RobotMode, SafetyMode, SetModeAction, SetModeFeedback, SetModeResult
from ur_msgs import srv as ur_srv
from ur_msgs.msg import Analog, Digital, IOStates, ToolDataMsg

from .. import sim_params
from ..node_loop import main as node_main
from ..node_loop import run_at_rate
from . import cartesian
from . import controller_manager as cm
from . import joints
from . import robot_state as rs
from . import urscript
from .dashboard import DashboardServices
from .settings import read_settings
from .trajectory import GoalError, Point
from .trajectory_controller import TrajectoryController

NODE = 'ur_hardware_interface'

# ros_controllers/ur_controllers types that run FollowJointTrajectory goals, and whether they scale.
TRAJECTORY_TYPES = {
    'position_controllers/ScaledJointTrajectoryController': True,
    'velocity_controllers/ScaledJointTrajectoryController': True,
    'position_controllers/JointTrajectoryController': False,
    'velocity_controllers/JointTrajectoryController': False,
    # Executed by the robot's own interpolation, which follows the speed slider.
    'pass_through_controllers/JointTrajectoryController': True,
}
PASS_THROUGH_TYPES = ('pass_through_controllers/JointTrajectoryController',
                      'pass_through_controllers/CartesianTrajectoryController')
CARTESIAN_TYPES = ('pass_through_controllers/CartesianTrajectoryController',
                   'pose_controllers/CartesianTrajectoryController',
                   'position_controllers/CartesianTrajectoryController')
VELOCITY_GROUP_TYPE = 'velocity_controllers/JointGroupVelocityController'
TWIST_TYPE = 'ros_controllers_cartesian/TwistController'
E_SERIES_SOFTWARE = (5, 12, 0, 0)
CB3_SOFTWARE = (3, 15, 7, 0)
SET_MODE_TIMEOUT = 30.0
# The read-only controllers of the config and what each publishes.
READ_ONLY = ('joint_state_controller', 'speed_scaling_state_controller', 'force_torque_sensor_controller')


class ArmSim(object):
    def __init__(self, rospy, get_param=None):
        self.rospy = rospy
        self.lock = threading.RLock()
        settings = read_settings(get_param or rospy.get_param)
        self.prefix, self.joints, self.loop_hz = settings.prefix, settings.joints, settings.loop_hz
        self.manager, self.arm, self.e_series = settings.manager, settings.arm, settings.e_series
        self.robot = settings.robot
        self.q = settings.initial
        self.servo_lag = settings.servo_lag
        self.streaming = False
        self.qd = np.zeros(6)

        self.trajectory_controllers = {}
        self.cartesian_controllers = {}
        for name, controller in self.manager.controllers.items():
            section = controller.section
            if controller.type in TRAJECTORY_TYPES:
                self.trajectory_controllers[name] = TrajectoryController(
                    self.joints, _prefixed(section.get('constraints', {}), self.prefix),
                    section.get('stop_trajectory_duration', 0.0), TRAJECTORY_TYPES[controller.type],
                    self.arm.lower, self.arm.upper, self.arm.velocity)
            elif controller.type in CARTESIAN_TYPES:
                # Not configured in ur_robot_driver's file: the position controllers' goal time
                # and stopped velocity; Cartesian tolerances are not checked.
                self.cartesian_controllers[name] = TrajectoryController(
                    self.joints, {'goal_time': 0.6, 'stopped_velocity_tolerance': 0.05}, 0.5, True,
                    self.arm.lower, self.arm.upper, self.arm.velocity)
        self.goal_handles = {}       # (controller, goal id) -> ServerGoalHandle
        self.group_velocity = np.zeros(6)
        self.twist = np.zeros(6)
        self.twist_follower = cartesian.TwistFollower(self.arm)
        self.twisting = False
        self.script_move = None      # (JointMove, elapsed s) of a movej from script_command
        self.script_queue = []
        self.limit_factor = 1.0
        self.wrench_zero = np.zeros(6)
        # The controller_stopper acts on the first cycle too: a robot that starts without
        # its program running starts with the commanding controllers stopped.
        self.last_program_running = True
        self.last_modes = None
        self.stopped_by_program = []
        self.finished = []           # (controller, goal handle, Outcome) to report outside self.lock
        self.published_running = None

        # -- publishers
        self.joint_states = rospy.Publisher('joint_states', JointState, queue_size=10)
        self.speed_scaling = rospy.Publisher('speed_scaling_factor', Float64, queue_size=10)
        self.wrench = rospy.Publisher('wrench', WrenchStamped, queue_size=10)
        self.io_states = rospy.Publisher('~io_states', IOStates, queue_size=10)
        self.tool_data = rospy.Publisher('~tool_data', ToolDataMsg, queue_size=10)
        self.program_running_pub = rospy.Publisher('~robot_program_running', Bool, queue_size=1, latch=True)
        self.robot_mode_pub = rospy.Publisher('~robot_mode', RobotMode, queue_size=1, latch=True)
        self.safety_mode_pub = rospy.Publisher('~safety_mode', SafetyMode, queue_size=1, latch=True)
        self.tf = tf2_ros.TransformBroadcaster()
        # joint_trajectory_controller's topics; the pass-through controllers have only their action.
        self.streaming_controllers = [name for name in self.trajectory_controllers
                                      if self.manager.controllers[name].type not in PASS_THROUGH_TYPES]
        self.state_pubs = {name: rospy.Publisher(name + '/state', JointTrajectoryControllerState, queue_size=10)
                           for name in self.streaming_controllers}

        # -- the hardware interface's services and topics
        self.dashboard = DashboardServices(rospy, self.robot, self.lock, self.e_series)
        rospy.Service('~hand_back_control', Trigger, lambda req: self._locked(self.robot.hand_back_control))
        rospy.Service('~resend_robot_program', Trigger, self._resend_robot_program)
        rospy.Service('~set_speed_slider', ur_srv.SetSpeedSliderFraction, self._set_speed_slider)
        rospy.Service('~set_io', ur_srv.SetIO, self._set_io)
        rospy.Service('~set_analog_output', ur_srv.SetAnalogOutput, lambda req: (self._locked(
            self.robot.set_io, 3, req.data.pin, req.data.state)[0],))
        # The simulation has no trajectory forwarding of its own to switch: the flag is kept and reported.
        self.spline_interpolation = True
        rospy.Service('~activate_spline_interpolation', SetBool, self._activate_spline_interpolation)
        rospy.Service('~set_payload', ur_srv.SetPayload, self._set_payload)
        rospy.Service('~zero_ftsensor', Trigger, self._zero_ftsensor)
        rospy.Service('~get_robot_software_version', ur_srv.GetRobotSoftwareVersion,
                      lambda req: E_SERIES_SOFTWARE if self.e_series else CB3_SOFTWARE)
        rospy.Subscriber('~script_command', String, self._script_command, queue_size=10)

        # -- controller_manager
        rospy.Service('controller_manager/list_controllers', cm_srv.ListControllers, self._list_controllers)
        rospy.Service('controller_manager/switch_controller', cm_srv.SwitchController, self._switch_controller)
        rospy.Service('controller_manager/list_controller_types', cm_srv.ListControllerTypes,
                      lambda req: (sorted(cm.CLAIMS) + ['joint_state_controller/JointStateController'],
                                   ['controller_interface::ControllerBase'] * (len(cm.CLAIMS) + 1)))
        rospy.Service('controller_manager/load_controller', cm_srv.LoadController,
                      lambda req: (req.name in self.manager.controllers,))
        rospy.Service('controller_manager/unload_controller', cm_srv.UnloadController,
                      lambda req: (False,))
        rospy.Service('controller_manager/reload_controller_libraries', cm_srv.ReloadControllerLibraries,
                      lambda req: (False,))

        # -- the controllers' own interfaces
        self.servers = {}
        for name in self.trajectory_controllers:
            server = actionlib.ActionServer(name + '/follow_joint_trajectory', FollowJointTrajectoryAction,
                                            self._trajectory_goal(name), self._trajectory_cancel(name),
                                            auto_start=False)
            self.servers[name] = server
            if name in self.streaming_controllers:
                rospy.Subscriber(name + '/command', JointTrajectory, self._trajectory_command(name), queue_size=1)
                rospy.Service(name + '/query_state', QueryTrajectoryState, self._query_state(name))
        for name in self.cartesian_controllers:
            server = actionlib.ActionServer(name + '/follow_cartesian_trajectory', FollowCartesianTrajectoryAction,
                                            self._cartesian_goal(name), self._trajectory_cancel(name),
                                            auto_start=False)
            self.servers[name] = server
        for name, controller in self.manager.controllers.items():
            if controller.type == VELOCITY_GROUP_TYPE:
                rospy.Subscriber(name + '/command', Float64MultiArray, self._group_velocity(name), queue_size=1)
            elif controller.type == TWIST_TYPE:
                rospy.Subscriber(name + '/command', Twist, self._twist(name), queue_size=1)
        self.set_mode = actionlib.SimpleActionServer('~set_mode', SetModeAction, self._set_mode, auto_start=False)
        for server in self.servers.values():
            server.start()
        self.set_mode.start()
        for name in self.trajectory_controllers:
            if self.manager.controllers[name].running:
                self.trajectory_controllers[name].start(self.q)

    # -- helpers ---------------------------------------------------------------------

    def _locked(self, call, *args):
        with self.lock:
            return call(*args)

    def _set_speed_slider(self, request):
        ok, message = self._locked(self.robot.set_speed_slider, request.speed_slider_fraction)
        if not ok:
            self.rospy.logerr('set_speed_slider: %s' % message)
        return (ok,)

    def _set_io(self, request):
        ok, message = self._locked(self.robot.set_io, request.fun, request.pin, request.state)
        if not ok:
            self.rospy.logerr('set_io: %s' % message)
        return (ok,)

    def _resend_robot_program(self, request):
        if not self.robot.headless:
            self.rospy.logwarn('resend_robot_program: ur_robot_driver offers this service with headless_mode:=true '
                               'only; without it, the real robot starts External Control by dashboard/play')
        return self._locked(self.robot.resend_robot_program)

    def _activate_spline_interpolation(self, request):
        self.spline_interpolation = bool(request.data)
        return True, ('Activated' if request.data else 'Deactivated') + \
            ' spline interpolation in forward trajectory mode.'

    def _query_state(self, name):
        def on_query(request):
            with self.lock:
                controller = self.trajectory_controllers[name]
                if not self.manager.controllers[name].running or controller.spline is None:
                    # joint_trajectory_controller answers false: the client sees a failed call.
                    self.rospy.logerr("Can't sample trajectory. Controller is not running.")
                    return None
                ahead = max(0.0, (request.time - self.rospy.Time.now()).to_sec())
                position, velocity, acceleration = controller.spline.sample(controller.clock + ahead)
            return self.joints, position.tolist(), velocity.tolist(), acceleration.tolist()
        return on_query

    def _set_payload(self, request):
        c = request.center_of_gravity
        ok, message = self._locked(self.robot.set_payload, request.mass, (c.x, c.y, c.z))
        if not ok:
            self.rospy.logerr('set_payload: %s' % message)
        return (ok,)

    def _zero_ftsensor(self, request):
        if not self.e_series:
            message = ('Zeroing the Force-Torque sensor is only available for e-Series robots (Major version >= 5). '
                       "This robot's version is %s" % '.'.join(str(v) for v in CB3_SOFTWARE))
            self.rospy.logerr(message)
            return False, message
        with self.lock:
            self.wrench_zero = np.zeros(6)  # remote control is always on in the simulation
        return True, ''

    # -- controller_manager ------------------------------------------------------------

    def _list_controllers(self, request):
        with self.lock:
            listing = self.manager.listing()
        return ([ControllerState(name=name, state=state, type=ctype,
                                 claimed_resources=[HardwareInterfaceResources(hardware_interface=interface,
                                                                               resources=joints)]
                                 if interface else [])
                 for name, state, ctype, interface, joints in listing],)

    def _switch_controller(self, request):
        with self.lock:
            if not self.robot.program_running:
                # ur_robot_driver's hardware interface refuses, whatever the strictness.
                claiming = [name for name in request.start_controllers if name in self.manager.controllers and
                            self.manager.controllers[name].commanding]
                if claiming:
                    self.rospy.logerr("Robot control is currently inactive. Starting controllers that claim "
                                      "resources is currently not possible. Not starting controller '%s'"
                                      % claiming[0])
                    return (False,)
            before = {c.name for c in self.manager.running_commanding()}
            ok, message = self.manager.switch(list(request.start_controllers), list(request.stop_controllers),
                                              request.strictness)
            if ok:
                after = {c.name for c in self.manager.running_commanding()}
                for name in before - after:
                    self._controller_stopped(name)
                for name in after - before:
                    self._controller_started(name)
                self.stopped_by_program = [n for n in self.stopped_by_program if n not in request.start_controllers]
        self._report()
        if message:
            (self.rospy.logwarn if ok else self.rospy.logerr)('switch_controller: %s' % message)
        return (ok,)

    def _controller_started(self, name):
        controller = self.trajectory_controllers.get(name) or self.cartesian_controllers.get(name)
        if controller is not None:
            controller.start(self.q)
        self.group_velocity = np.zeros(6)
        self.twist = np.zeros(6)

    def _controller_stopped(self, name):
        controller = self.trajectory_controllers.get(name) or self.cartesian_controllers.get(name)
        if controller is not None:
            outcome = controller.stop(self.q, self.qd)
            if outcome is not None:
                self._finish(name, outcome)
        self.group_velocity = np.zeros(6)
        self.twist = np.zeros(6)

    # -- trajectory controllers ------------------------------------------------------------

    def _result(self, name, code, message):
        result_type = FollowCartesianTrajectoryResult if name in self.cartesian_controllers \
            else FollowJointTrajectoryResult
        return result_type(error_code=getattr(result_type, code), error_string=message)

    def _refuse(self, name, handle, code, message):
        self.rospy.logerr('%s: %s' % (name, message))
        if self.manager.controllers[name].type in PASS_THROUGH_TYPES:
            # pass_through_controllers serve a simple action server: a goal is accepted, then aborted.
            handle.set_accepted()
            handle.set_aborted(self._result(name, code, message), message)
        else:
            handle.set_rejected(self._result(name, code, message), message)

    def _trajectory_goal(self, name):
        def on_goal(handle):
            goal = handle.get_goal()
            trajectory = goal.trajectory
            points = [Point(p.time_from_start.to_sec(), p.positions, p.velocities, p.accelerations)
                      for p in trajectory.points]
            with self.lock:
                if not self.manager.controllers[name].running:
                    return self._refuse(name, handle, 'INVALID_GOAL', "Can't accept new action goals. "
                                        "Controller is not running.")
                if not trajectory.points:
                    # An empty trajectory stops the current one (joint_trajectory_controller).
                    self._cancel_active(name)
                    handle.set_accepted()
                    handle.set_succeeded(self._result(name, 'SUCCESSFUL', ''))
                    return
                self._start_goal(name, handle, trajectory.joint_names, points, trajectory.header.stamp,
                                 goal.path_tolerance, goal.goal_tolerance, goal.goal_time_tolerance.to_sec())
            self._report()
        return on_goal

    def _start_goal(self, name, handle, joint_names, points, stamp, path_tolerance=(), goal_tolerance=(),
                    goal_time_tolerance=0.0):
        controller = self.trajectory_controllers.get(name) or self.cartesian_controllers[name]
        delay = 0.0 if stamp.is_zero() else (stamp - self.rospy.Time.now()).to_sec()
        goal_id = handle.get_goal_id().id if handle is not None else None
        try:
            preempted = controller.accept(goal_id, joint_names, points, delay, self.q, self.qd,
                                          path_tolerance, goal_tolerance, goal_time_tolerance)
        except GoalError as error:
            if handle is None:
                self.rospy.logerr('%s/command: %s' % (name, error))
                return
            return self._refuse(name, handle, error.code, str(error))
        if preempted is not None:
            self._finish(name, preempted)
        if handle is not None:
            handle.set_accepted()
            self.goal_handles[(name, goal_id)] = handle

    def _cancel_active(self, name):
        controller = self.trajectory_controllers.get(name) or self.cartesian_controllers[name]
        if controller.goal is not None:
            outcome = controller.cancel(controller.goal.goal_id, self.q, self.qd)
            self._finish(name, outcome)
        else:
            controller.start(self.q)

    def _trajectory_cancel(self, name):
        def on_cancel(handle):
            with self.lock:
                controller = self.trajectory_controllers.get(name) or self.cartesian_controllers[name]
                outcome = controller.cancel(handle.get_goal_id().id, self.q, self.qd)
                if outcome is not None:
                    self._finish(name, outcome)
            self._report()
        return on_cancel

    def _trajectory_command(self, name):
        def on_command(trajectory):
            points = [Point(p.time_from_start.to_sec(), p.positions, p.velocities, p.accelerations)
                      for p in trajectory.points]
            with self.lock:
                if not self.manager.controllers[name].running:
                    self.rospy.logerr("%s/command: Can't accept new commands. Controller is not running." % name)
                    return
                if not points:
                    self._cancel_active(name)
                    return
                controller = self.trajectory_controllers[name]
                if controller.goal is not None and controller.goal.goal_id is not None:
                    self._finish(name, controller.cancel(controller.goal.goal_id, self.q, self.qd))
                self._start_goal(name, None, trajectory.joint_names, points, trajectory.header.stamp)
            self._report()
        return on_command

    def _finish(self, name, outcome):
        """Queue a goal's end; _report() tells actionlib once self.lock is released."""
        handle = self.goal_handles.pop((name, outcome.goal_id), None)
        if handle is not None:
            self.finished.append((name, handle, outcome))

    def _report(self):
        # actionlib calls the goal and cancel callbacks holding its own lock, and they take
        # self.lock: so a thread holding self.lock must never wait for actionlib's lock.
        with self.lock:
            finished, self.finished = self.finished, []
        for name, handle, outcome in finished:
            result = self._result(name, outcome.code, outcome.message)
            if outcome.status == 'succeeded':
                handle.set_succeeded(result, outcome.message)
            elif outcome.status == 'aborted':
                self.rospy.logwarn('%s: goal aborted: %s' % (name, outcome.message))
                handle.set_aborted(result, outcome.message)
            else:
                handle.set_canceled(result, outcome.message)

    # -- Cartesian controllers ---------------------------------------------------------------

    def _cartesian_goal(self, name):
        def on_goal(handle):
            goal = handle.get_goal()
            with self.lock:
                running = self.manager.controllers[name].running
                start = self.q.copy()
            if not running:
                return self._refuse(name, handle, 'INVALID_GOAL', "Can't accept new action goals. "
                                    "Controller is not running.")
            # Inverse kinematics along the path takes a while: outside the lock, from
            # the joints where the holding controller keeps them.
            try:
                points = self._cartesian_points(goal.trajectory.points, start)
            except GoalError as error:
                return self._refuse(name, handle, error.code, str(error))
            with self.lock:
                self._start_goal(name, handle, self.joints, points, goal.trajectory.header.stamp,
                                 goal_time_tolerance=goal.goal_time_tolerance.to_sec())
            self._report()
        return on_goal

    def _cartesian_points(self, points, start):
        """Joint-space points for a Cartesian trajectory (its points in the base frame)."""
        return cartesian.joint_path(self.arm, [cartesian.Waypoint(
            p.time_from_start.to_sec(), (p.pose.position.x, p.pose.position.y, p.pose.position.z),
            (p.pose.orientation.w, p.pose.orientation.x, p.pose.orientation.y, p.pose.orientation.z))
            for p in points], start)

    # -- velocity and twist -------------------------------------------------------------------

    def _group_velocity(self, name):
        def on_command(msg):
            with self.lock:
                if not self.manager.controllers[name].running:
                    return
                if len(msg.data) != len(self.joints):
                    self.rospy.logerr('Dimension of command (%d) does not match number of joints (%d)! '
                                      'Not executing!' % (len(msg.data), len(self.joints)))
                    return
                if not all(math.isfinite(v) for v in msg.data):
                    self.rospy.logerr('%s/command: NaN or infinite velocity: not executing' % name)
                    return
                self.group_velocity = np.array(msg.data, dtype=float)
        return on_command

    def _twist(self, name):
        def on_command(msg):
            values = [msg.linear.x, msg.linear.y, msg.linear.z, msg.angular.x, msg.angular.y, msg.angular.z]
            with self.lock:
                if not self.manager.controllers[name].running:
                    return
                if not all(math.isfinite(v) for v in values):
                    self.rospy.logerr('%s/command: NaN or infinite twist: not executing' % name)
                    return
                self.twist = np.array(values)
        return on_command

    # -- script_command ---------------------------------------------------------------------

    def _script_command(self, msg):
        try:
            secondary, statements = urscript.parse(msg.data)
        except urscript.ScriptError as exc:
            self.rospy.logerr('script_command: the robot would not compile this script: %s' % exc)
            return
        with self.lock:
            if self.robot.robot_mode != rs.RUNNING:
                self.rospy.logerr('script_command: the robot is %s; it runs programs only when RUNNING'
                                  % self.robot.robot_mode)
                return
            self.robot.script_started(secondary)
            self.script_queue = list(statements) if not secondary else self.script_queue
            if secondary:
                for statement in statements:
                    self._run_statement(statement)

    def _run_statement(self, statement):
        """Run an immediate statement; a movej becomes the current script motion (True)."""
        name, args = statement.name, statement.args
        if name == 'movej':
            target, a, v, t = urscript.movej_arguments(statement)
            if isinstance(target, urscript.Pose):
                target = self.arm.inverse(cartesian.pose_from_ur_pose(target), self.q)
                if target is None:
                    self.rospy.logerr('script_command: movej: the pose is out of reach; program stopped')
                    self.script_queue = []
                    return False
            target = np.asarray(target, dtype=float)
            if np.any(target < self.arm.lower) or np.any(target > self.arm.upper):
                self.rospy.logerr('script_command: movej: target beyond the joint limits; program stopped')
                self.script_queue = []
                return False
            self.script_move = [urscript.JointMove(self.q, target, a, v, t, self.arm.velocity), 0.0]
            return True
        if name in ('set_standard_digital_out', 'set_digital_out', 'set_configurable_digital_out',
                    'set_tool_digital_out'):
            offset = {'set_configurable_digital_out': 8, 'set_tool_digital_out': 16}.get(name, 0)
            self.robot.set_io(1, int(args[0]) + offset, 1.0 if args[1] else 0.0)
        elif name in ('set_standard_analog_out', 'set_analog_out'):
            self.robot.set_io(3, int(args[0]), float(args[1]))
        elif name == 'set_tool_voltage':
            self.robot.set_io(4, 0, float(args[0]))
        elif name in ('textmsg', 'popup'):
            self.robot.log.append(' '.join(str(a) for a in args))
        return False

    # -- set_mode (robot_state_helper) ---------------------------------------------------------

    def _set_mode(self, goal):
        result = SetModeResult()
        names = {getattr(RobotMode, n): n for n in dir(RobotMode)
                 if n.isupper() and isinstance(getattr(RobotMode, n), int)}
        target = names.get(goal.target_robot_mode.mode)
        if target is None:
            result.success, result.message = False, 'Requested illegal mode.'
            return self.set_mode.set_aborted(result, result.message)
        with self.lock:
            try:
                steps = rs.plan_set_mode(self.robot.robot_mode, target, goal.stop_program)
            except ValueError as exc:
                result.success, result.message = False, str(exc)
                return self.set_mode.set_aborted(result, result.message)
        for command, wait_for in steps:
            self.dashboard.command(command)
            if wait_for is not None and not self._wait(lambda: self.robot.robot_mode == wait_for):
                if self.set_mode.is_preempt_requested():
                    return self.set_mode.set_preempted()
                result.success = False
                result.message = 'Timeout or preemption while waiting for robot mode %s' % wait_for
                return self.set_mode.set_aborted(result, result.message)
        if target == rs.RUNNING and goal.play_program:
            with self.lock:
                if self.robot.headless:
                    self.robot.resend_robot_program()
                else:
                    self.robot.dashboard('play')
            if not self._wait(lambda: self.robot.program_running):
                result.success, result.message = False, 'The program did not start'
                return self.set_mode.set_aborted(result, result.message)
        result.success, result.message = True, 'Reached target robot mode.'
        self.set_mode.set_succeeded(result, result.message)

    def _wait(self, condition):
        feedback = SetModeFeedback()
        end = self.rospy.get_time() + SET_MODE_TIMEOUT
        rate = self.rospy.Rate(20)
        while not self.rospy.is_shutdown() and self.rospy.get_time() < end:
            with self.lock:
                done = condition()
                feedback.current_robot_mode = getattr(RobotMode, self.robot.robot_mode)
                feedback.current_safety_mode = getattr(SafetyMode, self.robot.safety_mode)
            self.set_mode.publish_feedback(feedback)
            if done:
                return True
            if self.set_mode.is_preempt_requested():
                return False
            rate.sleep()
        return False

    # -- the control cycle -----------------------------------------------------------------------

    def step(self, dt):
        with self.lock:
            self.robot.step(dt)
            self._controller_stopper()
            self.streaming = False
            command = self._command(dt)
            # Streamed positions go through servoj's smoothing; the robot's own motions
            # (movej, speedj for the velocity and twist controllers, holding still) do not.
            self.q, self.qd = joints.follow(self.q, command, dt, self.servo_lag if self.streaming else 0.0,
                                            self.arm.velocity, self.arm.lower, self.arm.upper)
            scaling = self.robot.speed_scaling() * self.limit_factor
            q, qd = self.q.copy(), self.qd.copy()
            running = self.robot.program_running
            modes = (self.robot.robot_mode, self.robot.safety_mode)
            io = (list(self.robot.digital_in), list(self.robot.digital_out), list(self.robot.analog_in),
                  list(self.robot.analog_out), self.robot.tool_voltage)
            states = [(name, controller) for name, controller in self.trajectory_controllers.items()
                      if self.manager.controllers[name].running and name in self.state_pubs]
            state_samples = [(name, controller.spline.sample(controller.clock) if controller.spline else None)
                             for name, controller in states]
            # The read-only controllers publish while they run, as on the robot.
            reading = {name for name in READ_ONLY if name in self.manager.controllers and
                       self.manager.controllers[name].running}
        self._report()
        self._publish(q, qd, scaling, running, modes, io, state_samples, reading)

    def _controller_stopper(self):
        running = self.robot.program_running
        if running == self.last_program_running:
            return
        if not running:
            self.stopped_by_program = [c.name for c in self.manager.running_commanding()]
            if self.stopped_by_program:
                self.manager.switch([], self.stopped_by_program, cm.STRICT)
                for name in self.stopped_by_program:
                    self._controller_stopped(name)
        elif self.stopped_by_program:
            ok, _ = self.manager.switch(self.stopped_by_program, [], cm.BEST_EFFORT)
            for name in self.stopped_by_program:
                if self.manager.controllers[name].running:
                    self._controller_started(name)
            self.stopped_by_program = []
        self.last_program_running = running

    def _command(self, dt):
        self.limit_factor = 1.0
        command = self._controller_command(dt)
        if not self.twisting:
            self.twist_follower.reset()
        return command

    def _controller_command(self, dt):
        self.twisting = False
        if self.robot.robot_mode != rs.RUNNING:
            self.script_move = None
            self.script_queue = []
            return self.q
        if self.script_move is not None or self.script_queue:
            return self._script_step(dt)
        if not self.robot.program_running:
            return self.q
        scaling = self.robot.speed_scaling()
        for controller in self.manager.running_commanding():
            trajectory = self.trajectory_controllers.get(controller.name) or \
                self.cartesian_controllers.get(controller.name)
            if trajectory is not None:
                position, _, outcomes = trajectory.update(dt, scaling, self.q, self.qd)
                self.limit_factor = trajectory.limit_factor
                self.streaming = True
                for outcome in outcomes:
                    self._finish(controller.name, outcome)
                return position
            if controller.type == VELOCITY_GROUP_TYPE:
                return self.q + self.group_velocity * dt
            if controller.type == TWIST_TYPE:
                self.twisting = True
                return self.twist_follower.step(self.q, self.twist * scaling, dt)
        return self.q

    def _script_step(self, dt):
        while self.script_move is None and self.script_queue:
            self._run_statement(self.script_queue.pop(0))
        if self.script_move is None:
            return self.q
        move = self.script_move
        move[1] += dt * self.robot.speed_slider
        target = move[0].position(move[1])
        if move[1] >= move[0].total_time:
            self.script_move = None
        return target

    def _publish(self, q, qd, scaling, running, modes, io, state_samples, reading):
        now = self.rospy.Time.now()
        joint_state = JointState(name=self.joints, position=q.tolist(), velocity=qd.tolist(), effort=[0.0] * 6)
        joint_state.header.stamp = now
        if 'joint_state_controller' in reading:
            self.joint_states.publish(joint_state)
        pose = self.arm.forward(q)
        transform = TransformStamped()
        transform.header.stamp = now
        transform.header.frame_id = self.prefix + 'base'
        transform.child_frame_id = self.prefix + 'tool0_controller'
        transform.transform.translation.x, transform.transform.translation.y, transform.transform.translation.z = \
            pose[:3, 3]
        w, x, y, z = mat2quat(pose[:3, :3])
        transform.transform.rotation.w, transform.transform.rotation.x = w, x
        transform.transform.rotation.y, transform.transform.rotation.z = y, z
        self.tf.sendTransform(transform)
        if 'speed_scaling_state_controller' in reading:
            self.speed_scaling.publish(Float64(data=scaling))
        wrench = WrenchStamped()
        wrench.header.stamp = now
        wrench.header.frame_id = self.prefix + 'tool0_controller'
        if 'force_torque_sensor_controller' in reading:
            self.wrench.publish(wrench)
        digital_in, digital_out, analog_in, analog_out, tool_voltage = io
        self.io_states.publish(IOStates(
            digital_in_states=[Digital(pin=i, state=s) for i, s in enumerate(digital_in)],
            digital_out_states=[Digital(pin=i, state=s) for i, s in enumerate(digital_out)],
            flag_states=[],
            analog_in_states=[Analog(pin=i, domain=Analog.VOLTAGE, state=s)
                              for i, s in enumerate(analog_in)],
            analog_out_states=[Analog(pin=i, domain=Analog.CURRENT, state=s)
                               for i, s in enumerate(analog_out)]))
        self.tool_data.publish(ToolDataMsg(
            tool_mode=ToolDataMsg.TOOL_RUNNING_MODE if modes[0] != rs.POWER_OFF
            else ToolDataMsg.TOOL_IDLE_MODE, tool_output_voltage=tool_voltage))
        if running != self.published_running:
            self.program_running_pub.publish(Bool(data=running))
            self.published_running = running
        if modes != self.last_modes:
            self.robot_mode_pub.publish(RobotMode(mode=getattr(RobotMode, modes[0])))
            self.safety_mode_pub.publish(SafetyMode(mode=getattr(SafetyMode, modes[1])))
            self.last_modes = modes
        for name, sample in state_samples:
            if sample is None:
                continue
            state = JointTrajectoryControllerState(joint_names=self.joints)
            state.header.stamp = now
            state.desired.positions, state.desired.velocities = sample[0].tolist(), sample[1].tolist()
            state.actual.positions, state.actual.velocities = q.tolist(), qd.tolist()
            state.error.positions = (sample[0] - q).tolist()
            state.error.velocities = (sample[1] - qd).tolist()
            self.state_pubs[name].publish(state)


def _prefixed(constraints, prefix):
    return {(prefix + key if isinstance(value, dict) else key): value for key, value in (constraints or {}).items()}


def main():
    def run(rospy):
        try:
            sim = ArmSim(rospy)
        except sim_params.ParamError as exc:
            rospy.logfatal('%s: %s' % (NODE, exc))
            return 1
        longest_step = 10.0 / sim.loop_hz
        clock = {'last': rospy.get_time()}

        def step():
            now = rospy.get_time()
            sim.step(min(max(now - clock['last'], 0.0), longest_step))
            clock['last'] = now

        def restart_clock():
            clock['last'] = rospy.get_time()

        return run_at_rate(rospy, sim.loop_hz, step, on_time_jump=restart_clock)
    return node_main(NODE, run)
