"""The simulated UR controller and ur_robot_driver's side of it, without ROS: everything the robot decides.

ArmCore is stepped with the control period and returns a Snapshot of what
the driver publishes; requests (services, actions, command topics) are
plain method calls with plain results. The ROS node (arm_sim.py) only
converts messages and calls it, holding one lock around every call. What
it covers, as ur_robot_driver 2.4.1 documents it (ROS_INTERFACE.md,
controllers.md, features.md):

- the controller_manager over the controllers of config/<ur_type>_controllers.yaml:
  listing and switching, and the controller_stopper of ur_control.launch
  (when the program stops the commanding controllers stop, and they start
  again when it runs);
- the robot: modes, program, speed slider, IO, payload, safety
  (robot_state.RobotState), its dashboard server, and robot_state_helper's
  set_mode (SetModeRun);
- URScript on script_command: the urscript package's interpreter runs the
  program, script_robot.py is what its calls do to the robot (motion,
  force mode, state, set-up, IO);
- the trajectory controllers (scaled or not, pass-through) and the
  Cartesian ones: goals accepted, refused, preempted, cancelled, ended;
  joint_group_vel_controller and twist_controller.

The joints move behind one seam (joints.py): every cycle the core makes one
JointCommand and hands it to the joints object it was given, whichever
implementation that is. Nothing moves the arm until a controller or a
program commands it: the joints hold their start pose. When the joints
report a protective stop, the robot enters PROTECTIVE_STOP, its program
pauses and the arm holds until "unlock protective stop" and "play".
"""

import collections
import math

import numpy as np

from . import cartesian
from . import controller_manager as cm
from . import joints as jm
from . import robot_state as rs
from ... import urscript
from . import script_robot
from . import tcp_wrench
from .trajectory import GoalError
from .trajectory_controller import TrajectoryController

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
# Not configured in ur_robot_driver's file for the Cartesian controllers: the position
# controllers' goal time, stopped velocity and stop duration; Cartesian tolerances are not checked.
CARTESIAN_CONSTRAINTS = {'goal_time': 0.6, 'stopped_velocity_tolerance': 0.05}
CARTESIAN_STOP_DURATION = 0.5
# The read-only controllers of the config, each publishing one topic while it runs.
READ_ONLY = ('joint_state_controller', 'speed_scaling_state_controller', 'force_torque_sensor_controller')
# How long robot_state_helper's set_mode waits for each mode (and the program) it asked for, s.
SET_MODE_TIMEOUT = 30.0
# Log levels of the lines the core has to say (the node writes them to rosout).
ERROR, WARN, INFO = 'error', 'warn', 'info'
PROGRAM_STARTED, PROGRAM_STOPPED, RUNTIME_EXCEPTION = 'PROGRAM_STARTED', 'PROGRAM_STOPPED', 'RUNTIME_EXCEPTION'
TEXT = 'TEXT'  # a program's textmsg
# A program's text messages the primary interface's clients get per control cycle: a loop of textmsg without
# sync() writes up to 200 lines a cycle, which would overflow a client's queue and end its connection. The
# robot's log keeps every line.
TEXT_MESSAGES_PER_CYCLE = 10
PROGRAM_EVENTS = 100  # program events kept for the faces between two cycles
# How far back (s) the controller's history of joints and wrench reaches (URScript's
# get_actual_joint_positions_history, tool_contact). The manual gives no bound; a second is ours.
HISTORY_SECONDS = 1.0

# What became of a goal that ended: the controller, the goal id the request gave, its Outcome.
Finished = collections.namedtuple('Finished', 'controller goal_id outcome')


class GoalReply(object):
    """The answer to a new goal at once.

    `status`: 'accepted' (its end comes later, as a Finished), 'rejected', or
    'aborted' / 'succeeded' (accepted and ended at once); `code` names a
    FollowJointTrajectoryResult (or FollowCartesianTrajectoryResult) constant.
    """

    __slots__ = ('status', 'code', 'message')

    def __init__(self, status, code='SUCCESSFUL', message=''):
        self.status, self.code, self.message = status, code, message

    def __repr__(self):
        return 'GoalReply(%s, %s, %r)' % (self.status, self.code, self.message)


class Snapshot(object):
    """What the driver publishes after one cycle, in plain numbers (controller joint order)."""

    __slots__ = ('position', 'velocity', 'effort', 'tool_pose', 'speed_scaling', 'reading', 'wrench',
                 'digital_in', 'digital_out', 'analog_in', 'analog_out', 'tool_voltage', 'tool_running',
                 'program_running', 'robot_mode', 'safety_mode', 'controller_states')


class SetModeRun(object):
    """robot_state_helper's set_mode in progress: poll(now) until it gives (success, message).

    The dashboard commands of the plan are sent one by one, each waiting for
    the robot mode it leads to; a command whose answer is not the expected one
    ends the goal, as robot_state_helper's dashboard calls do; then, for
    play_program, the program is started (headless mode: the program is sent
    again) and awaited.
    """

    def __init__(self, robot, steps=(), play=False, result=None):
        self.robot = robot
        self.steps = list(steps)
        self.play = play
        self.waiting = None   # (condition, deadline, failure message)
        self.result = result

    def poll(self, now):
        """None while under way; (success, message) once done. `now`: seconds, any monotonic origin."""
        while self.result is None:
            if self.waiting is not None:
                condition, deadline, failure = self.waiting
                if condition():
                    self.waiting = None
                elif now > deadline:
                    self.result = (False, failure)
                else:
                    return None
            elif self.steps:
                command, wait_for = self.steps.pop(0)
                if self._send(command) and wait_for is not None:
                    self.waiting = (lambda mode=wait_for: self.robot.robot_mode == mode, now + SET_MODE_TIMEOUT,
                                    'Timeout or preemption while waiting for robot mode %s' % wait_for)
            elif self.play:
                self.play = False
                if self.robot.headless:
                    ok, message = self.robot.resend_robot_program()
                    if not ok:
                        self.result = (False, message)
                elif not self._send('play'):
                    continue
                self.waiting = (lambda: self.robot.program_running, now + SET_MODE_TIMEOUT,
                                'The program did not start')
            else:
                self.result = (True, 'Reached target robot mode.')
        return self.result

    def _send(self, command):
        answer = self.robot.dashboard(command)
        if rs.answer_matches(answer, rs.EXPECTED_ANSWER[command]):
            return True
        self.result = (False, 'An error occurred while switching the robot mode. The respective dashboard service '
                              'returned non-success: %s' % answer)
        return False


class ArmCore(object):
    """The simulated controller; `settings` from settings.read_settings, `motion` the joints (joints.py)."""

    def __init__(self, settings, motion):
        self.joint_names = list(settings.joints)
        self.manager = settings.manager
        self.arm = settings.arm
        self.robot = settings.robot
        self.software = settings.software
        self.motion = motion
        self.trajectory_controllers = {}
        self.cartesian_controllers = {}
        for name, controller in self.manager.controllers.items():
            if controller.type in TRAJECTORY_TYPES:
                section = controller.section
                self.trajectory_controllers[name] = TrajectoryController(
                    self.joint_names, _prefixed(section.get('constraints', {}), settings.prefix),
                    section.get('stop_trajectory_duration', 0.0), TRAJECTORY_TYPES[controller.type],
                    self.arm.lower, self.arm.upper, self.arm.velocity)
            elif controller.type in CARTESIAN_TYPES:
                self.cartesian_controllers[name] = TrajectoryController(
                    self.joint_names, CARTESIAN_CONSTRAINTS, CARTESIAN_STOP_DURATION, True,
                    self.arm.lower, self.arm.upper, self.arm.velocity)
        # joint_trajectory_controller's own topics and query_state; the pass-through controllers have none.
        self.streaming_controllers = [name for name in self.trajectory_controllers
                                      if self.manager.controllers[name].type not in PASS_THROUGH_TYPES]
        self.group_velocity = np.zeros(6)
        self.twist = np.zeros(6)
        self.twist_follower = cartesian.TwistFollower(self.arm)
        self.socket_hosts = settings.script_socket_hosts  # where a program's sockets may reach beyond loopback
        self.modbus_port = int(settings.script_modbus_port)  # the port of the units its MODBUS client polls
        self.script_robot = script_robot.ScriptRobot(self)
        self.script_run = None       # urscript.Run of the primary program from script_command
        self.secondary_runs = []     # urscript.Run of the secondary programs running beside it
        self.held = np.array(motion.position, dtype=float)  # where the arm holds while nothing commands
        self.tcp = np.eye(4)         # the TCP in the flange's frame (set_tcp)
        self.uptime = 0.0            # s of control cycles since the controller started
        # What the last cycle commanded the joints (RTDE's target_q and target_qd).
        self.target_position, self.target_velocity = np.array(motion.position, dtype=float), np.zeros(6)
        self.wrench_model = tcp_wrench.TcpWrench()
        # The last HISTORY_SECONDS of (joint positions, the TCP's wrench in base axes), one a cycle, newest
        # first: what get_actual_joint_positions_history and tool_contact look back through.
        self.history = collections.deque(
            maxlen=int(round(HISTORY_SECONDS / script_robot.STEP_TIME[self.software.generation])))
        # The controller's time (uptime) each RTDE input field was last written: rtde_set_watchdog's. The
        # fields RTDE takes are its face's to say (network_faces.py); without it no client writes any.
        self.rtde_input_times = {}
        self.rtde_inputs = None
        # The controller_stopper acts on the first cycle too: a robot that starts without
        # its program running starts with the commanding controllers stopped.
        self.last_program_running = True
        self.stopped_by_program = []
        self.finished = []           # Finished, for the node to report
        self.messages = []           # (level, text), for the node to log
        # What the controller tells its primary interface's clients of its programs: (PROGRAM_STARTED or
        # PROGRAM_STOPPED, the program's name) and (RUNTIME_EXCEPTION, line, column, text); the latest
        # only, for a host without such clients never takes them.
        self.program_events = collections.deque(maxlen=PROGRAM_EVENTS)
        self.script_name = None      # the running primary program's name
        for name in self.trajectory_controllers:
            if self.manager.controllers[name].running:
                self.trajectory_controllers[name].start(self.held)

    # -- what the node collects after each call -----------------------------------------------

    def take_finished(self):
        finished, self.finished = self.finished, []
        return finished

    def take_messages(self):
        messages, self.messages = self.messages, []
        return messages

    def take_program_events(self):
        events = list(self.program_events)
        self.program_events.clear()
        return events

    def say_warning(self, text):
        """A warning of the robot's, for the node's log (what its MODBUS client found, for one)."""
        self._say(WARN, text)

    def _say(self, level, text):
        self.messages.append((level, text))

    def _flange(self):
        return self.arm.forward(np.array(self.motion.position, dtype=float))

    def tcp_force(self, flange_pose=None):
        """(base axes, TCP axes): the robot's own external wrench at its TCP (tcp_wrench.py).

        `flange_pose`: the flange's pose now, where the caller has it (default: computed here).
        """
        flange = self.motion.flange_wrench
        if flange is None:
            return np.zeros(6), np.zeros(6)
        pose = self._flange() if flange_pose is None else flange_pose
        return self.wrench_model.at_tcp(flange, pose[:3, :3], self.tcp, self.robot.payload)

    def actual_state(self):
        """(positions, velocities) of the joints now, as copies."""
        return np.array(self.motion.position, dtype=float), np.array(self.motion.velocity, dtype=float)

    # -- the hardware interface's services -------------------------------------------------------

    def software_version(self):
        """get_robot_software_version: (major, minor, bugfix, build)."""
        return self.software.version

    def zero_ftsensor(self):
        """(success, message); refused below software version 5, as ur_robot_driver refuses it."""
        refusal = self.software.zero_ftsensor_refusal()
        if refusal is not None:
            self._say(ERROR, refusal)
            return False, refusal
        self.zero_tcp_wrench()
        return True, ''

    def zero_tcp_wrench(self):
        """URScript's zero_ftsensor(), which both generations have (the driver's service is the e-Series' only)."""
        self.wrench_model.zero(self.motion.flange_wrench, self._flange()[:3, :3], self.robot.payload)

    def dashboard(self, command):
        """The Dashboard Server's answer to one command line."""
        return self.robot.dashboard(command)

    def hand_back_control(self):
        return self.robot.hand_back_control()

    def resend_robot_program(self):
        if not self.robot.headless:
            self._say(WARN, 'resend_robot_program: ur_robot_driver offers this service with headless_mode:=true '
                            'only; without it, the real robot starts External Control by dashboard/play')
        return self.robot.resend_robot_program()

    def set_speed_slider(self, fraction):
        return self._checked('set_speed_slider', self.robot.set_speed_slider(fraction))

    def set_io(self, fun, pin, state):
        return self._checked('set_io', self.robot.set_io(fun, pin, state))

    def set_analog_output(self, pin, state):
        return self._checked('set_analog_output', self.robot.set_io(3, pin, state))

    def set_payload(self, mass, center_of_gravity):
        return self._checked('set_payload', self.robot.set_payload(mass, center_of_gravity))

    def _checked(self, service, result):
        ok, message = result
        if not ok:
            self._say(ERROR, '%s: %s' % (service, message))
        return ok, message

    @staticmethod
    def activate_spline_interpolation(active):
        """The simulation has no trajectory forwarding of its own to switch: the answer only."""
        return True, ('Activated' if active else 'Deactivated') + ' spline interpolation in forward trajectory mode.'

    def set_mode(self, target, stop_program, play_program):
        """robot_state_helper's set_mode towards robot mode `target` (a name; None: no robot mode): a SetModeRun."""
        if target is None:
            return SetModeRun(self.robot, result=(False, 'Requested illegal mode.'))
        try:
            steps = rs.plan_set_mode(self.robot.robot_mode, target, stop_program, self.robot.safety_mode)
        except ValueError as exc:
            return SetModeRun(self.robot, result=(False, str(exc)))
        return SetModeRun(self.robot, steps, play=target == rs.RUNNING and play_program)

    # -- controller_manager -----------------------------------------------------------------------

    def list_controllers(self):
        """[(name, state, type, hardware interface or None, claimed joints)] in load order."""
        return self.manager.listing()

    @staticmethod
    def controller_types():
        """list_controller_types: (types, base classes)."""
        types = sorted(cm.CLAIMS) + ['joint_state_controller/JointStateController']
        return types, ['controller_interface::ControllerBase'] * len(types)

    def load_controller(self, name):
        """Every controller the simulation has is loaded at start-up: True for those."""
        return name in self.manager.controllers

    def switch_controllers(self, start, stop, strictness):
        """controller_manager's switch_controller: (ok, message)."""
        if not self.robot.program_running:
            claiming = [name for name in start if name in self.manager.controllers and
                        self.manager.controllers[name].commanding]
            if claiming:
                # ur_robot_driver's hardware interface refuses, whatever the strictness.
                message = ("Robot control is currently inactive. Starting controllers that claim resources is "
                           "currently not possible. Not starting controller '%s'" % claiming[0])
                self._say(ERROR, message)
                return False, message
        before = {c.name for c in self.manager.running_commanding()}
        ok, message = self.manager.switch(list(start), list(stop), strictness)
        if ok:
            after = {c.name for c in self.manager.running_commanding()}
            for name in before - after:
                self._controller_stopped(name)
            for name in after - before:
                self._controller_started(name)
            self.stopped_by_program = [n for n in self.stopped_by_program if n not in start]
        if message:
            self._say(WARN if ok else ERROR, 'switch_controller: %s' % message)
        return ok, message

    def _controller_started(self, name):
        controller = self._trajectory(name)
        if controller is not None:
            controller.start(self.actual_state()[0])
        self.group_velocity = np.zeros(6)
        self.twist = np.zeros(6)

    def _controller_stopped(self, name):
        controller = self._trajectory(name)
        if controller is not None:
            outcome = controller.stop(*self.actual_state())
            if outcome is not None:
                self._finish(name, outcome)
        self.group_velocity = np.zeros(6)
        self.twist = np.zeros(6)

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
            self.manager.switch(self.stopped_by_program, [], cm.BEST_EFFORT)
            for name in self.stopped_by_program:
                if self.manager.controllers[name].running:
                    self._controller_started(name)
            self.stopped_by_program = []
        self.last_program_running = running

    # -- trajectory and Cartesian controllers ------------------------------------------------------

    def _trajectory(self, name):
        return self.trajectory_controllers.get(name) or self.cartesian_controllers.get(name)

    def refuse(self, name, code, message):
        """A goal `name` will not run: rejected, or, by the pass-through controllers' simple action
        server, accepted and aborted."""
        self._say(ERROR, '%s: %s' % (name, message))
        if self.manager.controllers[name].type in PASS_THROUGH_TYPES:
            return GoalReply('aborted', code, message)
        return GoalReply('rejected', code, message)

    def trajectory_goal(self, name, goal_id, joint_names, points, start_delay=0.0, path_tolerance=(),
                        goal_tolerance=(), goal_time_tolerance=0.0):
        """A new goal of controller `name`: a GoalReply; its end later comes as a Finished.

        `points`: trajectory.Point; `start_delay`: header.stamp minus now (s, 0
        for a zero stamp); the tolerances: trajectory.JointTolerance lists.
        """
        if not self.manager.controllers[name].running:
            return self.refuse(name, 'INVALID_GOAL', "Can't accept new action goals. Controller is not running.")
        if not points and name in self.trajectory_controllers:
            # An empty trajectory stops the current one (joint_trajectory_controller).
            self._cancel_active(name)
            return GoalReply('succeeded')
        return self._start_goal(name, goal_id, joint_names, points, start_delay, path_tolerance, goal_tolerance,
                                goal_time_tolerance)

    def _start_goal(self, name, goal_id, joint_names, points, start_delay, path_tolerance=(), goal_tolerance=(),
                    goal_time_tolerance=0.0):
        position, velocity = self.actual_state()
        try:
            preempted = self._trajectory(name).accept(goal_id, joint_names, points, start_delay, position, velocity,
                                                      path_tolerance, goal_tolerance, goal_time_tolerance)
        except GoalError as error:
            if goal_id is None:
                self._say(ERROR, '%s/command: %s' % (name, error))
                return None
            return self.refuse(name, error.code, str(error))
        if preempted is not None:
            self._finish(name, preempted)
        return GoalReply('accepted')

    def cancel_goal(self, name, goal_id):
        """A cancel request: the goal, if it is the active one, stops within stop_trajectory_duration."""
        outcome = self._trajectory(name).cancel(goal_id, *self.actual_state())
        if outcome is not None:
            self._finish(name, outcome)

    def _cancel_active(self, name):
        controller = self._trajectory(name)
        position, velocity = self.actual_state()
        if controller.goal is not None:
            self._finish(name, controller.cancel(controller.goal.goal_id, position, velocity))
        else:
            controller.start(position)

    def trajectory_command(self, name, joint_names, points, start_delay=0.0):
        """joint_trajectory_controller's command topic: replaces any goal; empty: stop."""
        if not self.manager.controllers[name].running:
            self._say(ERROR, "%s/command: Can't accept new commands. Controller is not running." % name)
            return
        if not points:
            self._cancel_active(name)
            return
        controller = self.trajectory_controllers[name]
        if controller.goal is not None and controller.goal.goal_id is not None:
            self._finish(name, controller.cancel(controller.goal.goal_id, *self.actual_state()))
        self._start_goal(name, None, joint_names, points, start_delay)

    def query_state(self, name, ahead):
        """query_state: (positions, velocities, accelerations) `ahead` s from now, or None (not running)."""
        controller = self.trajectory_controllers[name]
        if not self.manager.controllers[name].running or controller.spline is None:
            self._say(ERROR, "Can't sample trajectory. Controller is not running.")
            return None
        position, velocity, acceleration = controller.spline.sample(controller.clock + max(0.0, ahead))
        return position.tolist(), velocity.tolist(), acceleration.tolist()

    def cartesian_goal_start(self, name):
        """(a GoalReply refusing it, None), or (None, the joints' position the path is planned from)."""
        if not self.manager.controllers[name].running:
            return self.refuse(name, 'INVALID_GOAL', "Can't accept new action goals. Controller is not running."), None
        return None, self.actual_state()[0]

    def cartesian_points(self, waypoints, start):
        """Joint-space Points along a Cartesian path (cartesian.Waypoint in the base frame); GoalError.

        Reads only the arm's kinematics: the node calls it outside its lock, as it takes a while.
        """
        return cartesian.joint_path(self.arm, waypoints, start)

    def _finish(self, name, outcome):
        if outcome.goal_id is not None:
            self.finished.append(Finished(name, outcome.goal_id, outcome))

    # -- velocity and twist ----------------------------------------------------------------------

    def group_velocity_command(self, name, values):
        if not self.manager.controllers[name].running:
            return
        if len(values) != len(self.joint_names):
            self._say(ERROR, 'Dimension of command (%d) does not match number of joints (%d)! Not executing!'
                      % (len(values), len(self.joint_names)))
            return
        if not all(math.isfinite(v) for v in values):
            self._say(ERROR, '%s/command: NaN or infinite velocity: not executing' % name)
            return
        self.group_velocity = np.array(values, dtype=float)

    def twist_command(self, name, values):
        """A twist (base frame: linear x, y, z, then angular x, y, z)."""
        if not self.manager.controllers[name].running:
            return
        if not all(math.isfinite(v) for v in values):
            self._say(ERROR, '%s/command: NaN or infinite twist: not executing' % name)
            return
        self.twist = np.array(values, dtype=float)

    # -- URScript ---------------------------------------------------------------------------------

    @property
    def script_running(self):
        """A primary program from script_command runs (it replaced External Control)."""
        return self.script_run is not None

    def robot_log(self, text):
        """A line of the robot's log (textmsg, popup), which the node also writes to rosout."""
        self.robot.add_log(text)
        self._say(INFO, 'robot log: %s' % text)

    def program_text(self, text):
        """A program's textmsg: a line of the robot's log, and a text message to the primary interface's
        clients, as the controller sends one between the program's start and end."""
        self.robot_log(text)
        if sum(1 for event in self.program_events if event[0] == TEXT) < TEXT_MESSAGES_PER_CYCLE:
            self.program_events.append((TEXT, text))

    def script_command(self, text):
        """A program on script_command: a primary one replaces the running program, a secondary runs beside."""
        self.start_program(self.compile_program(text))

    def compile_program(self, text):
        """The Program of `text`, or the CompileError the robot refuses it with. It reads nothing a cycle
        changes, so hosts call it without the core's lock: a long program parses for tenths of a second, and
        the control cycle and its streams do not wait for that."""
        try:
            return urscript.compile_script(text, self.script_robot.served())
        except urscript.CompileError as exc:
            return exc

    def start_program(self, program):
        """compile_program's answer runs, as script_command says."""
        if isinstance(program, urscript.CompileError):
            self._say(ERROR, 'script_command: the robot would not compile this script: %s' % program)
            return
        if self.robot.robot_mode != rs.RUNNING:
            self._say(ERROR, 'script_command: the robot is %s; it runs programs only when RUNNING'
                      % self.robot.robot_mode)
            return
        self.robot.script_started(program.secondary)
        if program.secondary:
            run = urscript.Run(program, self.script_robot)
            self._step_run(run, 0.0)
            if not run.finished:
                # One that ended here (done, or its runtime exception said) is not stepped, nor said, again.
                self.secondary_runs.append(run)
            return
        if self.script_run is not None:
            self.script_run.stop()
            self.program_events.append((PROGRAM_STOPPED, self.script_name))
        self.script_robot.start()
        self.script_run = urscript.Run(program, self.script_robot)
        # A program of bare statements has no name; the controller names it after nothing either.
        self.script_name = program.name or ''
        self.program_events.append((PROGRAM_STARTED, self.script_name))

    def run_external_control(self, program):
        """external_control.urp played and its URCap fetched `program` (compile_program's answer to the
        driver's script, or the URCap's popup text as a str): it runs as the loaded program, where without a
        URCap the simulation stands in for the driver's. Nothing happens if the program stopped meanwhile."""
        if not self.robot.external_control_running:
            return
        if isinstance(program, (str, urscript.CompileError)):
            text = program if isinstance(program, str) else 'the robot would not compile it: %s' % program
            self._say(ERROR, 'external_control.urp: %s' % text)
            self.robot.program_failed(text)
            return
        self.start_program(program)

    def _step_run(self, run, dt):
        """One cycle of a program; a runtime error is the robot's runtime exception, in its log."""
        run.step(dt)
        if run.error is not None:
            self._runtime_exception(run.error)

    def _runtime_exception(self, fault):
        self.program_events.append((RUNTIME_EXCEPTION, getattr(fault, 'line', 0), getattr(fault, 'column', 0),
                                    getattr(fault, 'text', str(fault))))
        # ur_client_library prints the robot's runtime exception over three lines: one here.
        text = ' '.join(line.strip() for line in str(fault).splitlines())
        self.robot.add_log(text)
        self._say(ERROR, 'script_command: %s; program stopped' % text)

    def _stop_script(self, reason):
        self._say(ERROR, 'script_command: %s; program stopped' % reason)
        self._end_script()

    def _end_script(self):
        if self.script_run is not None:
            self.script_run.stop()
            self.program_events.append((PROGRAM_STOPPED, self.script_name))
        self.script_run = None
        self.script_robot.finish()
        self.robot.script_finished()

    def _secondary_programs(self, dt):
        for run in list(self.secondary_runs):
            self._step_run(run, dt)
            if run.finished:
                self.secondary_runs.remove(run)

    def _script_command(self, dt):
        """This cycle's JointCommand of the primary program; its end makes the program stop."""
        run = self.script_run
        if self.robot.program_state == rs.STOPPED:
            # The dashboard's stop (or power off) ended it: a later play starts the loaded program, not this.
            self._end_script()
            return self._hold()
        if not self.robot.moving_allowed:
            # Paused (or protectively stopped): the program waits where it is.
            return self._hold()
        expired = self.script_robot.expired_watchdog()
        if expired is not None:
            action, text = expired
            if action == script_robot.WATCHDOG_STOP:
                self.robot.add_log(text)
                self._stop_script(text)
            else:
                self.robot.pause_program(text)
                self._say(ERROR, 'script_command: %s; program paused' % text)
            return self._hold()
        # The speed slider slows the program's time, its motions with it.
        dt = dt * self.robot.speed_slider
        self._step_run(run, dt)
        if run.error is not None:
            self._end_script()
            return self._hold()
        try:
            position = self.script_robot.command(dt)
        except urscript.RuntimeFault as exc:
            if not exc.line and run.running_position is not None:
                exc.line, exc.column = run.running_position
            run.stop()
            self._runtime_exception(exc)
            self._end_script()
            return self._hold()
        if run.finished and not self.script_robot.moving:
            self._end_script()
        return jm.JointCommand(jm.MOVE, position)

    # -- the control cycle ---------------------------------------------------------------------------

    def _hold(self):
        return jm.JointCommand(jm.HOLD, self.held)

    def _command(self, dt):
        """(JointCommand, the speed scaling's velocity-limit factor, whether the twist is followed)."""
        if self.robot.robot_mode != rs.RUNNING:
            if self.script_running:
                self._stop_script('the robot is %s' % self.robot.robot_mode)
            return self._hold(), 1.0, False
        if self.script_running:
            return self._script_command(dt), 1.0, False
        if not self.robot.program_running:
            return self._hold(), 1.0, False
        scaling = self.robot.speed_scaling()
        for controller in self.manager.running_commanding():
            trajectory = self._trajectory(controller.name)
            if trajectory is not None:
                position, velocity, outcomes = trajectory.update(dt, scaling, *self.actual_state())
                for outcome in outcomes:
                    self._finish(controller.name, outcome)
                return jm.JointCommand(jm.SERVO, position, velocity), trajectory.limit_factor, False
            if controller.type == VELOCITY_GROUP_TYPE:
                return jm.JointCommand(jm.VELOCITY, velocity=self.group_velocity * scaling), 1.0, False
            if controller.type == TWIST_TYPE:
                target = self.twist_follower.step(self.actual_state()[0], self.twist * scaling, dt)
                return jm.JointCommand(jm.MOVE, target), 1.0, True
        return self._hold(), 1.0, False

    def step(self, dt):
        """One control cycle of `dt` seconds: the Snapshot to publish."""
        self.robot.step(dt)
        self._controller_stopper()
        self._secondary_programs(dt)
        self.script_robot.modbus.cycle(dt)
        command, limit_factor, twisting = self._command(dt)
        if not self.robot.moving_allowed:
            # Stopped, paused or protectively stopped: the controllers ran (their time goes on,
            # as on the robot), the arm stands still.
            command, twisting = self._hold(), False
        if not twisting:
            self.twist_follower.reset()
        if command.mode != jm.HOLD:
            self.held = None
        elif self.held is None:
            self.held = np.array(self.motion.position, dtype=float)
            command = self._hold()
        self.motion.step(command, dt)
        self.uptime += dt
        self._remember_target(command)
        reason = self.motion.protective_stop
        if reason is not None and self.robot.safety_mode != rs.PROTECTIVE_STOP:
            self.robot.protective_stop(reason)
            self._say(ERROR, 'Protective stop: %s. The program is paused: remove the cause, then '
                             'dashboard/unlock_protective_stop (after 5 s) and dashboard/play' % reason)
        return self._snapshot(limit_factor)

    def _remember_target(self, command):
        if command.position is not None:
            self.target_position = np.array(command.position, dtype=float)
        else:  # VELOCITY: where the speeds took the joints
            self.target_position = np.array(self.motion.position, dtype=float)
        self.target_velocity = np.zeros(6) if command.velocity is None else np.array(command.velocity, dtype=float)

    def _snapshot(self, limit_factor):
        robot = self.robot
        snapshot = Snapshot()
        snapshot.position, snapshot.velocity = self.actual_state()
        snapshot.effort = np.array(self.motion.effort, dtype=float)
        flange_pose = self.arm.forward(snapshot.position)
        snapshot.tool_pose = flange_pose.dot(self.tcp)
        snapshot.speed_scaling = robot.speed_scaling() * limit_factor
        snapshot.reading = {name for name in READ_ONLY if name in self.manager.controllers and
                            self.manager.controllers[name].running}
        # The robot's own wrench, in tool0_controller (the TCP) as ur_robot_driver publishes it.
        in_base, in_tcp = self.tcp_force(flange_pose)
        snapshot.wrench = tuple(in_tcp)
        self.history.appendleft((snapshot.position, in_base))
        snapshot.digital_in, snapshot.digital_out = list(robot.digital_in), list(robot.digital_out)
        snapshot.analog_in, snapshot.analog_out = list(robot.analog_in), list(robot.analog_out)
        snapshot.tool_voltage = robot.tool_voltage
        snapshot.tool_running = robot.robot_mode != rs.POWER_OFF
        snapshot.program_running = robot.program_running
        snapshot.robot_mode, snapshot.safety_mode = robot.robot_mode, robot.safety_mode
        snapshot.controller_states = []
        for name in self.streaming_controllers:
            controller = self.trajectory_controllers[name]
            if self.manager.controllers[name].running and controller.spline is not None:
                desired, desired_velocity, _ = controller.spline.sample(controller.clock)
                snapshot.controller_states.append((name, desired, desired_velocity))
        return snapshot


def _prefixed(constraints, prefix):
    return {(prefix + key if isinstance(value, dict) else key): value for key, value in (constraints or {}).items()}
