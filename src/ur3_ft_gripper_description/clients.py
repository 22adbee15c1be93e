"""Small clients of the real drivers' interfaces, for the examples and for your own scripts.

Each speaks only what the real driver offers, so a script built on them runs
unchanged on the real cell and on the simulation (``sim:=true``, with or
without ``physics:=true``):

* ``UrArm``: ur_robot_driver's ``scaled_pos_joint_traj_controller``
  (control_msgs/FollowJointTrajectory), ``controller_manager/switch_controller``,
  ``twist_controller/command`` and ``joint_states``;
* ``Gripper2F``: Robotiq's register topics ``Robotiq2FGripperRobotOutput`` /
  ``Robotiq2FGripperRobotInput`` (2F-85 & 2F-140 manual, section 4);
* ``FT300``: rq_sensor's ``robotiq_ft_wrench`` and its ``robotiq_ft_sensor_acc``
  service (command_id 8: SET_ZERO);
* ``UrScript``: ur_robot_driver's ``script_command`` (URScript programs),
  ``robot_program_running``, the robot's own ``wrench`` and the dashboard's
  ``play``, which hands control back to External Control.

Where the tool goes is planned with ``ToolKinematics``: the arm's inverse
kinematics for the model in ``robot_description`` (yours, calibrated), for
the 2F-140's ``gripper_tcp``. Every wait ends, on time or with a
``CellError`` naming what did not happen.

Every wait for something the cell does is on ROS time (``rospy.get_time``,
``rospy.sleep``, the messages' stamps), never the wall clock: on a simulated
cell with ``use_sim_time`` they run unchanged at any real-time factor, and on
a busy machine they wait for the cell, which slows down with it. Only the
waits for the driver's nodes to be there (their servers, topics and first
messages) are on the wall clock, as ``rospy.wait_for_service`` is: a process
coming up takes wall time, however fast the cell's clock runs.
"""

import collections
import math
import threading
import time

import numpy as np

ARM_JOINTS = ('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
              'wrist_3_joint')
TRAJECTORY_CONTROLLER = 'scaled_pos_joint_traj_controller'
# ur_robot_driver's hardware interface node, as its bring-up names it.
HARDWARE_INTERFACE = '/ur_hardware_interface/'
STANDARD_GRAVITY = 9.80665
# Stamps this far (s) from a node's ROS time come from another clock: simulated time against the wall clock.
CLOCKS_APART = 3600.0


class CellError(RuntimeError):
    """Something the cell did not do; the message is one line."""


def wait_until(rospy, condition, what, timeout, step=0.01):
    """The first true value of condition(), or CellError naming `what` after `timeout` s of ROS time."""
    return _first_true(condition, what, timeout, step, rospy.get_time, rospy.sleep, rospy.is_shutdown)


def wait_until_up(rospy, condition, what, timeout, step=0.02):
    """The first true value of condition(), or CellError naming `what` after `timeout` s of wall-clock time:
    for a node of the driver to be there, which takes the same wall time at any real-time factor."""
    return _first_true(condition, what, timeout, step, time.monotonic, time.sleep, rospy.is_shutdown)


def _first_true(condition, what, timeout, step, now, sleep, shut_down):
    """condition()'s first true value, polled every `step` s of the clock `now`/`sleep`; CellError naming
    `what` once `timeout` s have passed on that clock or the node shuts down."""
    end = now() + timeout
    while True:
        value = condition()
        if value:
            return value
        if now() > end or shut_down():
            raise CellError('no %s within %g s' % (what, timeout))
        sleep(step)


class ToolKinematics(object):
    """Joint positions that put the 2F-140's gripper_tcp at a pose in base_link, from the model as loaded."""

    def __init__(self, rospy, prefix=''):
        from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics
        self.prefix = prefix
        self.joints = [prefix + name for name in ARM_JOINTS]
        self.arm = ArmKinematics(rospy.get_param('robot_description'), self.joints, prefix + 'base_link',
                                 prefix + 'gripper_tcp')

    def tool_down(self, x, y, z, yaw=0.0):
        """The 4x4 pose of gripper_tcp at (x, y, z) (m, base_link), pointing straight down, its pads closing
        along base_link's y axis turned by `yaw` (rad) about z (the arm's start pose has yaw 0)."""
        c, s = math.cos(yaw), math.sin(yaw)
        pose = np.eye(4)
        # Tool z down; the pads close along the tool's x, here (-s, c, 0).
        pose[:3, :3] = np.array([[-s, c, 0.0], [c, s, 0.0], [0.0, 0.0, -1.0]])
        pose[:3, 3] = (x, y, z)
        return pose

    def joints_for(self, pose, seed):
        """Joint positions (rad) within the limits for `pose`; CellError if out of reach.

        Of the arm's solutions (every branch, found in closed form whatever `seed` is), the one nearest
        `seed` in the seed's branch, each joint the short way round: a move from `seed` does not swing
        through a far configuration. Another branch only where the seed's does not reach.
        """
        q = self.arm.nearest_inverse(pose, seed)
        if q is None:
            raise CellError('the pose %s is out of the arm\'s reach' % np.round(pose[:3, 3], 3).tolist())
        return [float(v) for v in q]

    def tool_pose(self, positions):
        return self.arm.forward(positions)

    def path_to(self, seed, x, y, z, clear_height, yaw=0.0):
        """Joint waypoints from `seed` to the tool at (x, y, z) pointing down, passing at `clear_height`:
        straight up, over at that height, down. What stands on the table stays out of the way."""
        here = self.tool_pose(seed)[:3, 3]
        path = []
        for point in ((here[0], here[1], max(here[2], clear_height)), (x, y, max(z, clear_height)), (x, y, z)):
            seed = self.joints_for(self.tool_down(point[0], point[1], point[2], yaw), seed)
            path.append(seed)
        return path


class UrArm(object):
    """ur_robot_driver's joint trajectory controller, controller switching, twist controller and joint states."""

    def __init__(self, rospy, prefix='', timeout=60.0):
        import actionlib
        from control_msgs.msg import FollowJointTrajectoryAction
        from controller_manager_msgs.srv import SwitchController
        from geometry_msgs.msg import Twist
        from sensor_msgs.msg import JointState
        self.rospy = rospy
        self.joints = [prefix + name for name in ARM_JOINTS]
        self.positions = None
        self._lock = threading.Lock()
        rospy.Subscriber('joint_states', JointState, self._on_joint_state, queue_size=1)
        self.trajectory = actionlib.SimpleActionClient(TRAJECTORY_CONTROLLER + '/follow_joint_trajectory',
                                                       FollowJointTrajectoryAction)
        # Short waits on ROS time inside a wall-clock one: see wait_until_up.
        wait_until_up(rospy, lambda: self.trajectory.wait_for_server(rospy.Duration(0.01)),
                      'action server %s/follow_joint_trajectory (is the arm up?)' % TRAJECTORY_CONTROLLER, timeout)
        rospy.wait_for_service('controller_manager/switch_controller', timeout)
        self.switch = rospy.ServiceProxy('controller_manager/switch_controller', SwitchController)
        self.twist_publisher = rospy.Publisher('twist_controller/command', Twist, queue_size=1)
        from ur_dashboard_msgs.msg import SafetyMode
        self.safety_names = {getattr(SafetyMode, n): n for n in dir(SafetyMode) if n.isupper()}
        self.safety_mode = None
        rospy.Subscriber(HARDWARE_INTERFACE + 'safety_mode', SafetyMode,
                         lambda msg: setattr(self, 'safety_mode', self.safety_names.get(msg.mode)), queue_size=1)
        wait_until_up(rospy, lambda: self.positions is not None, 'joint_states of the arm', timeout)

    def _on_joint_state(self, msg):
        if self.joints[0] in msg.name:
            with self._lock:
                self.positions = [msg.position[msg.name.index(j)] for j in self.joints]

    def joint_positions(self):
        with self._lock:
            return list(self.positions)

    def move(self, positions, duration):
        """Go to `positions` (rad) in `duration` s through the scaled trajectory controller, ending at rest."""
        from control_msgs.msg import FollowJointTrajectoryGoal, FollowJointTrajectoryResult
        from trajectory_msgs.msg import JointTrajectoryPoint
        goal = FollowJointTrajectoryGoal()
        goal.trajectory.joint_names = self.joints
        goal.trajectory.points.append(JointTrajectoryPoint(
            positions=list(positions), velocities=[0.0] * 6, time_from_start=self.rospy.Duration(duration)))
        self.trajectory.send_goal(goal)
        end = self.rospy.get_time() + duration + 30.0
        while not self.trajectory.wait_for_result(self.rospy.Duration(0.1)):
            self.check_safety()
            if self.rospy.get_time() > end:
                raise CellError('the trajectory did not end within %g s' % (duration + 30.0))
        result = self.trajectory.get_result()
        if result.error_code != FollowJointTrajectoryResult.SUCCESSFUL:
            raise CellError('the trajectory failed: error_code %d %s' % (result.error_code, result.error_string))

    def check_safety(self):
        """CellError if the robot stopped itself (a protective stop, an emergency stop...)."""
        if self.safety_mode not in (None, 'NORMAL', 'REDUCED'):
            raise CellError('the robot stopped: safety mode %s' % self.safety_mode)

    def move_along(self, path, speed=0.5):
        """move_steadily() through each joint waypoint of `path` in turn."""
        for positions in path:
            self.move_steadily(positions, speed)

    def move_steadily(self, positions, speed=0.5, shortest=1.0):
        """move() taking as long as the largest joint motion needs at `speed` (rad/s), at least `shortest` s."""
        travel = max(abs(a - b) for a, b in zip(positions, self.joint_positions()))
        self.move(positions, max(shortest, travel / speed))

    def only(self, controller, stop):
        """Start `controller` and stop the controllers `stop` (controller_manager's switch, STRICT)."""
        from controller_manager_msgs.srv import SwitchControllerRequest
        reply = self.switch(SwitchControllerRequest(start_controllers=[controller], stop_controllers=list(stop),
                                                    strictness=SwitchControllerRequest.STRICT))
        if not reply.ok:
            raise CellError('controller_manager did not switch to %s' % controller)

    def twist(self, vx=0.0, vy=0.0, vz=0.0, wx=0.0, wy=0.0, wz=0.0):
        """A twist of the tool (m/s, rad/s, the robot's base frame) on twist_controller/command."""
        from geometry_msgs.msg import Twist
        message = Twist()
        message.linear.x, message.linear.y, message.linear.z = vx, vy, vz
        message.angular.x, message.angular.y, message.angular.z = wx, wy, wz
        self.twist_publisher.publish(message)


class Gripper2F(object):
    """A Robotiq 2F-85/2F-140 through its register topics: activate, go to a position, read the status."""

    # gOBJ (manual 4.4): 0 moving, 1 stopped on an object while opening, 2 while closing, 3 at the request.
    MOVING, OBJECT_OPENING, OBJECT_CLOSING, AT_REQUEST = 0, 1, 2, 3

    def __init__(self, rospy, timeout=30.0):
        from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input, Robotiq2FGripper_robot_output
        self.rospy = rospy
        self.output_type = Robotiq2FGripper_robot_output
        self.status = None
        self._received = 0
        self._condition = threading.Condition()
        rospy.Subscriber('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input, self._on_status, queue_size=10)
        self.publisher = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output,
                                         queue_size=10)
        wait_until_up(rospy, lambda: self.status is not None and self.publisher.get_num_connections(),
                      'gripper status and command subscriber', timeout)

    def _on_status(self, msg):
        with self._condition:
            self.status = msg
            self._received += 1
            self._condition.notify_all()

    def send(self, **registers):
        self.publisher.publish(self.output_type(**registers))

    def wait_status(self, check, what, timeout=10.0, skip=2):
        """The first status satisfying check(status), `skip` statuses after now (the command's effect)."""
        with self._condition:
            start = self._received
            end = self.rospy.get_time() + timeout
            while not (self._received >= start + skip and check(self.status)):
                if self.rospy.get_time() > end:
                    raise CellError('no gripper status with %s within %g s (last: gOBJ %d gPO %d gSTA %d)' % (
                        what, timeout, self.status.gOBJ, self.status.gPO, self.status.gSTA))
                # A short wall-clock wait: a status or the clock's advance ends it (ROS time may be simulated).
                self._condition.wait(0.05)
            return self.status

    def activate(self):
        """Reset, then activate (the fingers end open); returns the status."""
        self.send(rACT=0)
        self.wait_status(lambda s: s.gSTA == 0, 'gSTA 0 (reset)')
        self.send(rACT=1, rGTO=1, rPR=0, rSP=255, rFR=150)
        return self.wait_status(lambda s: s.gSTA == 3 and s.gOBJ == self.AT_REQUEST, 'gSTA 3 and gOBJ 3 (active)')

    def go(self, position, speed=255, force=150, timeout=10.0):
        """Move to register position 0..255 at rSP `speed`, rFR `force`; the status once the fingers stopped."""
        self.send(rACT=1, rGTO=1, rPR=position, rSP=speed, rFR=force)
        return self.wait_status(lambda s: s.gPR == position and s.gOBJ != self.MOVING,
                                'the fingers stopped (gOBJ 1, 2 or 3) for rPR %d' % position, timeout)


class WrenchRecord(object):
    """A WrenchStamped topic's readings by their stamps: (stamp s, (fx, fy, fz, tx, ty, tz)), the latest 3000."""

    # A cell on the simulated clock runs faster than real time: a client the machine starves for a moment
    # finds what came meanwhile in its queue.
    QUEUE = 1000

    def __init__(self, rospy, topic):
        from geometry_msgs.msg import WrenchStamped
        self.rospy, self.topic = rospy, topic
        self.readings = collections.deque(maxlen=3000)
        self._lock = threading.Lock()
        rospy.Subscriber(topic, WrenchStamped, self._on_wrench, queue_size=self.QUEUE)

    def _on_wrench(self, msg):
        f, t = msg.wrench.force, msg.wrench.torque
        with self._lock:
            self.readings.append((msg.header.stamp.to_sec(), (f.x, f.y, f.z, t.x, t.y, t.z)))

    def latest(self):
        with self._lock:
            return self.readings[-1][1]

    def since(self, start, end=float('inf')):
        """The readings stamped from `start` (s, ROS time) on, up to `end`."""
        with self._lock:
            return [w for t, w in self.readings if start <= t <= end]

    def mean_over(self, start, end):
        """The mean wrench stamped from `start` to `end` (s, ROS time), once a later reading arrived."""
        with self._lock:
            stamp = self.readings[-1][0] if self.readings else start
        if abs(stamp - start) > CLOCKS_APART:
            raise CellError('%s is stamped %.0f s away from this node\'s ROS time: run this node with the same '
                            'use_sim_time as the cell' % (self.topic, stamp - start))
        wait_until(self.rospy, lambda: self.readings and self.readings[-1][0] >= end,
                   '%s for %g s' % (self.topic, end - start), max(0.0, end - self.rospy.get_time()) + 10.0)
        readings = self.since(start, end)
        if not readings:
            raise CellError('no %s in %g s' % (self.topic, end - start))
        return mean_wrench(readings)


class FT300(object):
    """The Robotiq FT 300 through rq_sensor's interface: its wrench stream and SET_ZERO."""

    def __init__(self, rospy, timeout=30.0):
        from robotiq_ft_sensor.srv import sensor_accessor
        self.rospy = rospy
        self.record = WrenchRecord(rospy, 'robotiq_ft_wrench')
        rospy.wait_for_service('robotiq_ft_sensor_acc', timeout)
        self.accessor = rospy.ServiceProxy('robotiq_ft_sensor_acc', sensor_accessor)
        wait_until_up(rospy, lambda: self.record.readings, 'robotiq_ft_wrench', timeout)

    @property
    def readings(self):
        return self.record.readings

    def latest(self):
        return self.record.latest()

    def since(self, start, end=float('inf')):
        """The readings stamped from `start` (s, ROS time) on, up to `end`."""
        return self.record.since(start, end)

    def zero(self):
        """SET_ZERO (command_id 8): later readings are relative to the current one."""
        reply = self.accessor(command_id=8, command='')
        if not reply.success:
            raise CellError('robotiq_ft_sensor_acc refused SET_ZERO: %s' % reply.res)
        self.rospy.sleep(0.05)  # the next reading is the zeroed one

    def mean(self, seconds):
        """The mean wrench over the next `seconds` s."""
        start = self.rospy.get_time()
        return self.mean_over(start, start + seconds)

    def mean_over(self, start, end):
        """The mean wrench stamped from `start` to `end` (s, ROS time), once a later reading arrived."""
        return self.record.mean_over(start, end)


class UrScript(object):
    """URScript programs through ur_robot_driver: sent on script_command, run by the robot itself.

    A program (`def ...: ... end`) replaces the External Control program: the ROS controllers stop
    commanding until `resume()` plays it again (the dashboard's play; with headless_mode,
    resend_robot_program).
    """

    def __init__(self, rospy, timeout=30.0, headless=False):
        from std_msgs.msg import Bool, String
        self.rospy, self.headless, self.timeout = rospy, headless, timeout
        self.program_running = None
        self.wrench = WrenchRecord(rospy, 'wrench')  # the robot's own, in tool0_controller
        self.publisher = rospy.Publisher(HARDWARE_INTERFACE + 'script_command', String, queue_size=1)
        rospy.Subscriber(HARDWARE_INTERFACE + 'robot_program_running', Bool,
                         lambda msg: setattr(self, 'program_running', msg.data), queue_size=1)
        wait_until_up(rospy, lambda: self.publisher.get_num_connections() > 0, 'subscriber of script_command',
                      timeout)
        wait_until_up(rospy, lambda: self.program_running is not None, 'robot_program_running', timeout)

    def run(self, program):
        """Send `program` and wait until it replaced External Control (robot_program_running false)."""
        from std_msgs.msg import String
        self.publisher.publish(String(data=program))
        wait_until(self.rospy, lambda: self.program_running is False, 'start of the program sent', self.timeout)

    def wrench_since(self, start, end=float('inf')):
        """The robot's own wrench readings stamped from `start` (s, ROS time) to `end`."""
        return self.wrench.since(start, end)

    def resume(self):
        """External Control again: the ROS controllers command the arm."""
        from std_srvs.srv import Trigger
        name = HARDWARE_INTERFACE + ('resend_robot_program' if self.headless else 'dashboard/play')
        self.rospy.wait_for_service(name, self.timeout)
        reply = self.rospy.ServiceProxy(name, Trigger)()
        if not reply.success:
            raise CellError('%s refused: %s' % (name, reply.message))
        wait_until(self.rospy, lambda: self.program_running, 'External Control running again', self.timeout)


def mean_wrench(readings):
    """The mean of wrench readings (fx, fy, fz, tx, ty, tz); CellError if there are none."""
    if not readings:
        raise CellError('no wrench readings to average')
    return tuple(float(v) for v in np.mean(readings, axis=0))


def force_norm(wrench):
    return math.sqrt(sum(v * v for v in wrench[:3]))
