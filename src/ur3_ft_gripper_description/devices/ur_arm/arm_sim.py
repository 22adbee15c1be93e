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

This node only adapts: it converts messages and calls core.ArmCore, which
decides everything (see there), under one lock. The joints are
joints.KinematicJoints: they go where they are commanded, no faster than the
model's velocity limits; no dynamics, no collisions, no protective stops.

With ~physics true they move on MuJoCo instead (ur_arm.physics_joints): the
node hosts the physics cell (physics.host: built from robot_description in
~world_file, served to the FT 300 and 2F-140 nodes, its real-time factor on
/diagnostics) and steps it with its control loop.

With use_sim_time (the default with physics) the node is the cell's clock:
each control cycle is exactly one period of simulated time, published on
/clock, paced to the wall clock at ~real_time_factor (sim_clock,
node_loop.run_as_clock), and everything it publishes is stamped with it.
Without, the loop runs on the wall clock, each cycle as long as the time
since the last.
"""

import threading

import actionlib
from cartesian_control_msgs.msg import FollowCartesianTrajectoryAction, FollowCartesianTrajectoryResult
from control_msgs.msg import FollowJointTrajectoryAction, FollowJointTrajectoryResult, JointTrajectoryControllerState
from control_msgs.srv import QueryTrajectoryState
from controller_manager_msgs import srv as cm_srv
from controller_manager_msgs.msg import ControllerState, HardwareInterfaceResources
from geometry_msgs.msg import TransformStamped, Twist, WrenchStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64, Float64MultiArray, String
from std_srvs.srv import SetBool, Trigger
from tf2_msgs.msg import TFMessage
from trajectory_msgs.msg import JointTrajectory
from transforms3d.quaternions import mat2quat
from ur_dashboard_msgs.msg import RobotMode, SafetyMode, SetModeAction, SetModeFeedback, SetModeResult
from ur_msgs import srv as ur_srv
from ur_msgs.msg import Analog, Digital, IOStates, ToolDataMsg

from .. import node_loop, sim_clock, sim_params
from ..physics import link
from . import cartesian
from . import core as arm_core
from . import joints
from ..network import listen
from .dashboard import DashboardServices
from .network_faces import NetworkFaces
from .settings import PARAMETERS, read_settings
from .trajectory import GoalError, JointTolerance, Point

NODE = link.ARM_NODE
STATE_QUEUE = 500
ROBOT_MODES = {getattr(RobotMode, n): n for n in dir(RobotMode)
               if n.isupper() and isinstance(getattr(RobotMode, n), int)}


class ArmSim(object):
    def __init__(self, rospy, get_param=None):
        self.rospy = rospy
        self.lock = threading.RLock()
        get_param = get_param or rospy.get_param
        settings = read_settings(get_param)
        self.prefix, self.loop_hz = settings.prefix, settings.loop_hz
        # On simulated time the node is the clock: what it publishes carries the cycle's time.
        self.clock = sim_clock.SimClock(settings.loop_hz, settings.real_time_factor, stride=settings.clock_stride) \
            if settings.use_sim_time else None
        self.physics = None
        if sim_params.read(get_param, PARAMETERS, '~physics'):
            from ..physics.host import CellHost
            from .physics_joints import PhysicsJointMotion
            self.physics = CellHost(rospy, get_param, settings, self.lock,
                                    pace=settings.real_time_factor if self.clock else None)
            motion = PhysicsJointMotion.from_settings(self.physics.cell, settings)
        else:
            motion = joints.KinematicJoints.from_settings(settings)
        self.core = core = arm_core.ArmCore(settings, motion)
        self.goal_handles = {}       # (controller, goal id) -> ServerGoalHandle
        self.published = None        # (program running, robot mode, safety mode) last published on the latched topics
        self.joint_names = core.joint_names

        # -- publishers
        # A simulated second of states: faster than real time, a subscriber's turn comes in bursts, and
        # rospy drops what overflows a connection's queue.
        self.joint_states = node_loop.cycle_publisher(rospy, 'joint_states', JointState, STATE_QUEUE,
                                                      on_sim_clock=self.clock is not None)
        self.speed_scaling = rospy.Publisher('speed_scaling_factor', Float64, queue_size=10)
        self.wrench = rospy.Publisher('wrench', WrenchStamped, queue_size=STATE_QUEUE)
        self.io_states = rospy.Publisher('~io_states', IOStates, queue_size=10)
        self.tool_data = rospy.Publisher('~tool_data', ToolDataMsg, queue_size=10)
        self.program_running_pub = rospy.Publisher('~robot_program_running', Bool, queue_size=1, latch=True)
        self.robot_mode_pub = rospy.Publisher('~robot_mode', RobotMode, queue_size=1, latch=True)
        self.safety_mode_pub = rospy.Publisher('~safety_mode', SafetyMode, queue_size=1, latch=True)
        self.tf = rospy.Publisher('/tf', TFMessage, queue_size=100)  # as tf2_ros.TransformBroadcaster's
        self.state_pubs = {name: rospy.Publisher(name + '/state', JointTrajectoryControllerState, queue_size=10)
                           for name in core.streaming_controllers}

        # -- the hardware interface's services and topics
        self.dashboard = DashboardServices(rospy, core, self.lock)
        rospy.Service('~hand_back_control', Trigger, lambda req: self._call(core.hand_back_control))
        rospy.Service('~resend_robot_program', Trigger, lambda req: self._call(core.resend_robot_program))
        rospy.Service('~set_speed_slider', ur_srv.SetSpeedSliderFraction, lambda req: (self._call(
            core.set_speed_slider, req.speed_slider_fraction)[0],))
        rospy.Service('~set_io', ur_srv.SetIO, lambda req: (self._call(core.set_io, req.fun, req.pin, req.state)[0],))
        rospy.Service('~set_analog_output', ur_srv.SetAnalogOutput, lambda req: (self._call(
            core.set_analog_output, req.data.pin, req.data.state)[0],))
        rospy.Service('~activate_spline_interpolation', SetBool, lambda req: core.activate_spline_interpolation(
            req.data))
        rospy.Service('~set_payload', ur_srv.SetPayload, lambda req: (self._call(
            core.set_payload, req.mass, (req.center_of_gravity.x, req.center_of_gravity.y,
                                         req.center_of_gravity.z))[0],))
        rospy.Service('~zero_ftsensor', Trigger, lambda req: self._call(core.zero_ftsensor))
        rospy.Service('~get_robot_software_version', ur_srv.GetRobotSoftwareVersion,
                      lambda req: core.software_version())
        rospy.Subscriber('~script_command', String,
                         lambda msg: self._call(core.start_program, core.compile_program(msg.data)), queue_size=10)

        # -- controller_manager
        rospy.Service('controller_manager/list_controllers', cm_srv.ListControllers, self._list_controllers)
        rospy.Service('controller_manager/switch_controller', cm_srv.SwitchController, lambda req: (self._call(
            core.switch_controllers, req.start_controllers, req.stop_controllers, req.strictness)[0],))
        rospy.Service('controller_manager/list_controller_types', cm_srv.ListControllerTypes,
                      lambda req: core.controller_types())
        rospy.Service('controller_manager/load_controller', cm_srv.LoadController,
                      lambda req: (core.load_controller(req.name),))
        rospy.Service('controller_manager/unload_controller', cm_srv.UnloadController, lambda req: (False,))
        rospy.Service('controller_manager/reload_controller_libraries', cm_srv.ReloadControllerLibraries,
                      lambda req: (False,))

        # -- the controllers' own interfaces
        servers = []
        for name in core.trajectory_controllers:
            servers.append(actionlib.ActionServer(
                name + '/follow_joint_trajectory', FollowJointTrajectoryAction, self._trajectory_goal(name),
                self._cancel(name), auto_start=False))
            if name in core.streaming_controllers:
                rospy.Subscriber(name + '/command', JointTrajectory, self._trajectory_command(name), queue_size=1)
                rospy.Service(name + '/query_state', QueryTrajectoryState, self._query_state(name))
        for name in core.cartesian_controllers:
            servers.append(actionlib.ActionServer(
                name + '/follow_cartesian_trajectory', FollowCartesianTrajectoryAction, self._cartesian_goal(name),
                self._cancel(name), auto_start=False))
        for name, controller in core.manager.controllers.items():
            if controller.type == arm_core.VELOCITY_GROUP_TYPE:
                rospy.Subscriber(name + '/command', Float64MultiArray, lambda msg, name=name: self._call(
                    core.group_velocity_command, name, list(msg.data)), queue_size=1)
            elif controller.type == arm_core.TWIST_TYPE:
                rospy.Subscriber(name + '/command', Twist, lambda msg, name=name: self._call(
                    core.twist_command, name, [msg.linear.x, msg.linear.y, msg.linear.z,
                                               msg.angular.x, msg.angular.y, msg.angular.z]), queue_size=1)
        self.set_mode = actionlib.SimpleActionServer('~set_mode', SetModeAction, self._set_mode, auto_start=False)
        for server in servers:
            server.start()
        self.set_mode.start()
        self.action_status = ActionStatus(servers + [self.set_mode.action_server])

        # -- the controller's own network interfaces, on the same core and lock as the ROS interface
        self.network = None
        if settings.robot_ip:
            self.network = NetworkFaces(settings.robot_ip, core, self._call, rospy.logwarn)
            if not listen.is_loopback(settings.robot_ip):
                rospy.logwarn('%s: the controller\'s network interfaces listen on %s, beyond this machine'
                              % (NODE, settings.robot_ip))
            self.network.start()
            for server in self.network.servers:
                rospy.loginfo('%s: %s on %s:%d' % (NODE, server.name, *server.server_address[:2]))

    # -- calling the core --------------------------------------------------------------------

    def _call(self, method, *args):
        """method(*args) under the lock, then what the core has to say and report."""
        with self.lock:
            result = method(*args)
        self._report()
        return result

    def _report(self):
        # actionlib calls the goal and cancel callbacks holding its own lock, and they take
        # self.lock: so a thread holding self.lock must never wait for actionlib's lock.
        with self.lock:
            messages, finished = self.core.take_messages(), self.core.take_finished()
            handles = [(f, self.goal_handles.pop((f.controller, f.goal_id), None)) for f in finished]
        log = {arm_core.ERROR: self.rospy.logerr, arm_core.WARN: self.rospy.logwarn,
               arm_core.INFO: self.rospy.loginfo}
        for level, text in messages:
            log[level](text)
        for done, handle in handles:
            if handle is None:
                continue
            outcome = done.outcome
            result = self._result(done.controller, outcome.code, outcome.message)
            if outcome.status == 'succeeded':
                handle.set_succeeded(result, outcome.message)
            elif outcome.status == 'aborted':
                self.rospy.logwarn('%s: goal aborted: %s' % (done.controller, outcome.message))
                handle.set_aborted(result, outcome.message)
            else:
                handle.set_canceled(result, outcome.message)

    def _list_controllers(self, request):
        with self.lock:
            listing = self.core.list_controllers()
        return ([ControllerState(name=name, state=state, type=ctype,
                                 claimed_resources=[HardwareInterfaceResources(hardware_interface=interface,
                                                                               resources=joints)]
                                 if interface else [])
                 for name, state, ctype, interface, joints in listing],)

    # -- the controllers' goals and commands ---------------------------------------------------------

    def _result(self, name, code, message):
        result_type = FollowCartesianTrajectoryResult if name in self.core.cartesian_controllers \
            else FollowJointTrajectoryResult
        return result_type(error_code=getattr(result_type, code), error_string=message)

    def _answer(self, name, handle, goal_id, reply):
        """Tell actionlib the core's GoalReply to the goal of `handle`.

        Under self.lock, in actionlib's goal callback (which holds actionlib's lock): so no
        cycle can end an accepted goal before actionlib knows it was accepted.
        """
        if reply.status == 'accepted':
            self.goal_handles[(name, goal_id)] = handle
        if reply.status == 'rejected':
            return handle.set_rejected(self._result(name, reply.code, reply.message), reply.message)
        handle.set_accepted()
        if reply.status == 'aborted':
            handle.set_aborted(self._result(name, reply.code, reply.message), reply.message)
        elif reply.status == 'succeeded':
            handle.set_succeeded(self._result(name, reply.code, reply.message), reply.message)

    def now(self):
        """ROS time as the controllers see it: the clock's own on simulated time (its /clock reaches this
        node's rospy a moment later), else rospy's."""
        if self.clock is not None:
            return self.rospy.Time(*divmod(self.clock.nanoseconds, 1000000000))
        return self.rospy.Time.now()

    def _start_delay(self, stamp):
        return 0.0 if stamp.is_zero() else (stamp - self.now()).to_sec()

    def _trajectory_goal(self, name):
        def on_goal(handle):
            goal = handle.get_goal()
            trajectory = goal.trajectory
            goal_id = handle.get_goal_id().id
            with self.lock:
                reply = self.core.trajectory_goal(
                    name, goal_id, list(trajectory.joint_names), _points(trajectory.points),
                    self._start_delay(trajectory.header.stamp), _tolerances(goal.path_tolerance),
                    _tolerances(goal.goal_tolerance), goal.goal_time_tolerance.to_sec())
                self._answer(name, handle, goal_id, reply)
            self._report()
        return on_goal

    def _cartesian_goal(self, name):
        def on_goal(handle):
            goal = handle.get_goal()
            goal_id = handle.get_goal_id().id
            with self.lock:
                reply, start = self.core.cartesian_goal_start(name)
            if reply is None:
                # Inverse kinematics along the path takes a while: outside the lock, from
                # the joints where the holding controller keeps them.
                try:
                    points = self.core.cartesian_points([cartesian.Waypoint(
                        p.time_from_start.to_sec(), (p.pose.position.x, p.pose.position.y, p.pose.position.z),
                        (p.pose.orientation.w, p.pose.orientation.x, p.pose.orientation.y, p.pose.orientation.z))
                        for p in goal.trajectory.points], start)
                except GoalError as error:
                    with self.lock:
                        reply = self.core.refuse(name, error.code, str(error))
            with self.lock:
                if reply is None:
                    reply = self.core.trajectory_goal(
                        name, goal_id, self.joint_names, points, self._start_delay(goal.trajectory.header.stamp),
                        goal_time_tolerance=goal.goal_time_tolerance.to_sec())
                self._answer(name, handle, goal_id, reply)
            self._report()
        return on_goal

    def _cancel(self, name):
        return lambda handle: self._call(self.core.cancel_goal, name, handle.get_goal_id().id)

    def _trajectory_command(self, name):
        return lambda trajectory: self._call(self.core.trajectory_command, name, list(trajectory.joint_names),
                                             _points(trajectory.points), self._start_delay(trajectory.header.stamp))

    def _query_state(self, name):
        def on_query(request):
            ahead = (request.time - self.now()).to_sec()
            sample = self._call(self.core.query_state, name, ahead)
            # None: joint_trajectory_controller answers false, the client sees a failed call.
            return None if sample is None else (self.joint_names,) + sample
        return on_query

    # -- set_mode (robot_state_helper) ---------------------------------------------------------

    def _set_mode(self, goal):
        with self.lock:
            run = self.core.set_mode(ROBOT_MODES.get(goal.target_robot_mode.mode), goal.stop_program,
                                     goal.play_program)
        feedback = SetModeFeedback()
        rate = self.rospy.Rate(20)
        while not self.rospy.is_shutdown():
            with self.lock:
                done = run.poll(self.rospy.get_time())
                modes = self.core.robot.robot_mode, self.core.robot.safety_mode
            if done is not None:
                result = SetModeResult(success=done[0], message=done[1])
                return (self.set_mode.set_succeeded if done[0] else self.set_mode.set_aborted)(result, done[1])
            feedback.current_robot_mode = getattr(RobotMode, modes[0])
            feedback.current_safety_mode = getattr(SafetyMode, modes[1])
            self.set_mode.publish_feedback(feedback)
            if self.set_mode.is_preempt_requested():
                return self.set_mode.set_preempted()
            rate.sleep()

    # -- the control cycle -----------------------------------------------------------------------

    def step(self, dt, stamp):
        """One control cycle of `dt` s; what it publishes is stamped `stamp`, the time the cycle integrates to."""
        with self.lock:
            snapshot = self.core.step(dt)
            if self.network is not None:
                self.network.after_cycle(dt, snapshot)
        self._report()
        self._publish(snapshot, stamp)
        self.action_status.step(dt)
        if self.physics is not None:
            self.physics.after_step()

    def _publish(self, s, now):
        # A stream nobody subscribes to sends nothing, so its message is not built either (the latched
        # topics are, for whoever subscribes later).
        q, qd = s.position.tolist(), s.velocity.tolist()
        if 'joint_state_controller' in s.reading and self.joint_states.get_num_connections():
            joint_state = JointState(name=self.joint_names, position=q, velocity=qd, effort=s.effort.tolist())
            joint_state.header.stamp = now
            self.joint_states.publish(joint_state)
        if self.tf.get_num_connections():
            transform = TransformStamped()
            transform.header.stamp = now
            transform.header.frame_id = self.prefix + 'base'
            transform.child_frame_id = self.prefix + 'tool0_controller'
            translation, rotation = transform.transform.translation, transform.transform.rotation
            translation.x, translation.y, translation.z = s.tool_pose[:3, 3]
            rotation.w, rotation.x, rotation.y, rotation.z = mat2quat(s.tool_pose[:3, :3])
            self.tf.publish(TFMessage(transforms=[transform]))
        if 'speed_scaling_state_controller' in s.reading and self.speed_scaling.get_num_connections():
            self.speed_scaling.publish(Float64(data=s.speed_scaling))
        if 'force_torque_sensor_controller' in s.reading and self.wrench.get_num_connections():
            wrench = WrenchStamped()
            wrench.header.stamp = now
            wrench.header.frame_id = self.prefix + 'tool0_controller'
            force, torque = wrench.wrench.force, wrench.wrench.torque
            force.x, force.y, force.z, torque.x, torque.y, torque.z = s.wrench
            self.wrench.publish(wrench)
        if self.io_states.get_num_connections():
            self._publish_io(s)
        if self.tool_data.get_num_connections():
            self.tool_data.publish(ToolDataMsg(
                tool_mode=ToolDataMsg.TOOL_RUNNING_MODE if s.tool_running else ToolDataMsg.TOOL_IDLE_MODE,
                tool_output_voltage=s.tool_voltage))
        # The latched topics: published when they change, as the driver does.
        published = (s.program_running, s.robot_mode, s.safety_mode)
        if self.published is None or published[0] != self.published[0]:
            self.program_running_pub.publish(Bool(data=s.program_running))
        if self.published is None or published[1:] != self.published[1:]:
            self.robot_mode_pub.publish(RobotMode(mode=getattr(RobotMode, s.robot_mode)))
            self.safety_mode_pub.publish(SafetyMode(mode=getattr(SafetyMode, s.safety_mode)))
        self.published = published
        for name, desired, desired_velocity in s.controller_states:
            if not self.state_pubs[name].get_num_connections():
                continue
            state = JointTrajectoryControllerState(joint_names=self.joint_names)
            state.header.stamp = now
            state.desired.positions, state.desired.velocities = desired.tolist(), desired_velocity.tolist()
            state.actual.positions, state.actual.velocities = q, qd
            state.error.positions = (desired - s.position).tolist()
            state.error.velocities = (desired_velocity - s.velocity).tolist()
            self.state_pubs[name].publish(state)

    def _publish_io(self, s):
        self.io_states.publish(IOStates(
            digital_in_states=[Digital(pin=i, state=v) for i, v in enumerate(s.digital_in)],
            digital_out_states=[Digital(pin=i, state=v) for i, v in enumerate(s.digital_out)],
            flag_states=[],
            analog_in_states=[Analog(pin=i, domain=Analog.VOLTAGE, state=v) for i, v in enumerate(s.analog_in)],
            analog_out_states=[Analog(pin=i, domain=Analog.CURRENT, state=v) for i, v in enumerate(s.analog_out)]))


class ActionStatus(object):
    """The action servers' status topics, published from the control cycle at each server's own rate.

    actionlib gives every server a rospy.Timer for its status, and on
    simulated time rospy wakes every such timer's thread at each /clock tick
    to look at the time: with a server per controller, those wake-ups cost
    the node more than its control cycle. So the timers are stopped, and the
    cycle publishes each server's status at the rate actionlib read for it
    (actionlib_status_frequency, 5 Hz by default), in the same ROS time.
    """

    def __init__(self, servers):
        self.due = []  # [server, period (s), time since its last status (s)]
        for server in servers:
            if server.status_frequency > 0.0:
                server.status_timer.shutdown()
                self.due.append([server, 1.0 / server.status_frequency, 0.0])

    def step(self, dt):
        for entry in self.due:
            entry[2] += dt
            if entry[2] >= entry[1]:
                entry[2] -= entry[1]
                entry[0].publish_status()


def _points(points):
    return [Point(p.time_from_start.to_sec(), p.positions, p.velocities, p.accelerations) for p in points]


def _tolerances(tolerances):
    return [JointTolerance(t.name, t.position, t.velocity, t.acceleration) for t in tolerances]


def main():
    def run(rospy):
        from ...model.names import DescriptionError
        from ..physics import MissingMuJoCo
        from ..physics.world import WorldError
        try:
            sim = ArmSim(rospy)
        except (sim_params.ParamError, MissingMuJoCo, WorldError, DescriptionError, listen.ListenError) as exc:
            rospy.logfatal('%s: %s' % (NODE, exc))
            return 1
        if sim.network is not None:
            rospy.on_shutdown(sim.network.shutdown)
        if sim.clock is not None:
            return node_loop.run_as_clock(rospy, sim.clock, sim.step)
        # The wall clock: the time since the last cycle, at most ten periods, in the robot's own cycles.
        period = 1.0 / sim.loop_hz
        clock = {'last': rospy.get_time()}

        def step():
            now = rospy.get_time()
            late = now - clock['last']
            if late > sim_clock.LATE_AFTER_PERIODS * period:
                cycles = sim_clock.wall_cycles(late, period, 10.0 * period)
                behind = sum(cycles)
                for dt in cycles[:-1]:
                    behind -= dt
                    sim.step(dt, rospy.Time.from_sec(now - behind))
                late = cycles[-1]
            # Stamped with the time the cycle integrated to, not the time it publishes: a process
            # preempted in between would stamp a state later than the one it holds.
            sim.step(max(late, 0.0), rospy.Time.from_sec(now))
            clock['last'] = now

        def restart_clock():
            clock['last'] = rospy.get_time()

        return node_loop.run_at_rate(rospy, sim.loop_hz, step, on_time_jump=restart_clock)
    return node_loop.main(NODE, run)
