"""Soak of the simulated arm (bench/soak.py --what arm): the bring-up with sim:=true, driven for a long time.

Through ur_robot_driver's interface only, in a loop: a trajectory on the
scaled controller; a secondary URScript program that toggles outputs and
logs (textmsg) and a dashboard addToLog; a primary program (movej without a
and v) that stops External Control, then dashboard play, after which the
controller_stopper starts the controller again; switches to the unscaled
trajectory controller, joint_group_vel_controller and twist_controller, each
commanded, and back. Limits: ur_hardware_interface's resident memory grows by
at most 5 MB after the warm-up, and every goal and program succeeds.
"""
import os
import time

import benchlib
from ur3_ft_gripper_testing.ur_driver import AWAY, COMMANDING, HOME, HW, JOINTS

RSS_LIMIT_MB = 5.0
NODE = '/ur_hardware_interface'
TIMEOUT = 30.0


class Driver(object):
    """Clients of the simulated driver's documented interface."""

    def __init__(self, rospy):
        import actionlib
        from control_msgs.msg import FollowJointTrajectoryAction
        from controller_manager_msgs.srv import SwitchController
        from geometry_msgs.msg import Twist
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Bool, Float64MultiArray, String
        from std_srvs.srv import Trigger
        from ur_dashboard_msgs.srv import AddToLog
        self.rospy = rospy
        self.trajectory = {name: actionlib.SimpleActionClient(name + '/follow_joint_trajectory',
                                                              FollowJointTrajectoryAction)
                           for name in ('scaled_pos_joint_traj_controller', 'pos_joint_traj_controller')}
        for client in self.trajectory.values():
            if not client.wait_for_server(rospy.Duration(120)):
                raise RuntimeError('no action server %s' % client.action_client.ns)
        for name, kind in (('switch', ('controller_manager/switch_controller', SwitchController)),
                           ('play', (HW + 'dashboard/play', Trigger)),
                           ('add_to_log', (HW + 'dashboard/add_to_log', AddToLog))):
            rospy.wait_for_service(kind[0], TIMEOUT)
            setattr(self, name, rospy.ServiceProxy(*kind))
        self.script = rospy.Publisher(HW + 'script_command', String, queue_size=10)
        self.velocity = rospy.Publisher('joint_group_vel_controller/command', Float64MultiArray, queue_size=1)
        self.twist = rospy.Publisher('twist_controller/command', Twist, queue_size=1)
        self.program_running = None
        self.positions = None
        rospy.Subscriber(HW + 'robot_program_running', Bool, lambda msg: setattr(self, 'program_running', msg.data))
        rospy.Subscriber('joint_states', JointState, self._on_joints, queue_size=1)
        for publisher in (self.script, self.velocity, self.twist):
            benchlib.wait_for(publisher.get_num_connections, 'a subscriber of %s' % publisher.resolved_name, TIMEOUT)

    def _on_joints(self, msg):
        if JOINTS[0] in msg.name:
            self.positions = [msg.position[msg.name.index(j)] for j in JOINTS]

    def only(self, controller):
        from controller_manager_msgs.srv import SwitchControllerRequest
        request = SwitchControllerRequest(start_controllers=[controller],
                                          stop_controllers=[c for c in COMMANDING if c != controller],
                                          strictness=SwitchControllerRequest.BEST_EFFORT)
        return self.switch(request).ok

    def goal(self, controller, points):
        """Run a joint trajectory; its error code (0: SUCCESSFUL), or None without a result."""
        from control_msgs.msg import FollowJointTrajectoryGoal
        from trajectory_msgs.msg import JointTrajectoryPoint
        goal = FollowJointTrajectoryGoal()
        goal.trajectory.joint_names = JOINTS
        for seconds, positions in points:
            goal.trajectory.points.append(JointTrajectoryPoint(positions=positions,
                                                               time_from_start=self.rospy.Duration(seconds)))
        client = self.trajectory[controller]
        client.send_goal(goal)
        try:
            benchlib.wait_for_result(client, TIMEOUT)
        except AssertionError:
            return None
        return client.get_result().error_code

    def hold(self, publisher, command, release, seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            publisher.publish(command)
            time.sleep(0.02)
        publisher.publish(release)


def cycle(driver, index, problems):
    """One round of everything; each thing that went wrong is added to `problems`."""
    from geometry_msgs.msg import Twist
    from std_msgs.msg import Float64MultiArray, String

    from ur3_ft_gripper_description.number_text import number_list

    def check(ok, what):
        if not ok:
            problems.append('cycle %d: %s' % (index, what))
        return ok

    check(driver.only('scaled_pos_joint_traj_controller'), 'switch to scaled_pos_joint_traj_controller')
    check(driver.goal('scaled_pos_joint_traj_controller', [(1.5, AWAY), (3.0, HOME)]) == 0, 'scaled trajectory')
    on = index % 2 == 0
    # A hundred long log lines a cycle: kept whole, they would grow the node by ~20 MB in 30 minutes;
    # the robot's log reaches its bound (robot_state.LOG_ENTRIES) in the warm-up.
    lines = ''.join('  textmsg("soak cycle %d line %d %s")\n' % (index, n, 'x' * 1000) for n in range(100))
    driver.script.publish(String(data='sec io():\n  set_configurable_digital_out(%d, %s)\n  set_tool_digital_out(0, '
                                      '%s)\n%send' % (index % 8, on, on, lines)))
    check(driver.add_to_log('soak cycle %d' % index).success, 'dashboard add_to_log')
    target = list(HOME)
    target[0] += 0.3 if on else -0.3
    driver.script.publish(String(data='movej([%s])' % number_list(target)))
    arrived = wait(lambda: driver.positions and max(abs(a - b) for a, b in zip(driver.positions, target)) < 1e-6)
    check(arrived, 'movej to %s' % target)
    check(wait(lambda: driver.program_running is False), 'the script program replaces External Control')
    check(driver.play().success, 'dashboard play')
    check(wait(lambda: driver.program_running), 'External Control runs again')
    check(driver.only('pos_joint_traj_controller'), 'switch to pos_joint_traj_controller')
    check(driver.goal('pos_joint_traj_controller', [(1.5, HOME)]) == 0, 'unscaled trajectory')
    check(driver.only('joint_group_vel_controller'), 'switch to joint_group_vel_controller')
    speed = 0.1 if on else -0.1
    driver.hold(driver.velocity, Float64MultiArray(data=[speed, 0, 0, 0, 0, 0]),
                Float64MultiArray(data=[0.0] * 6), 0.5)
    check(driver.only('twist_controller'), 'switch to twist_controller')
    twist = Twist()
    twist.linear.z, twist.angular.z = (0.02, 0.1) if on else (-0.02, -0.1)
    driver.hold(driver.twist, twist, Twist(), 0.5)
    check(driver.only('scaled_pos_joint_traj_controller'), 'switch back to scaled_pos_joint_traj_controller')
    check(driver.goal('scaled_pos_joint_traj_controller', [(1.5, HOME)]) == 0, 'back home')


def wait(condition, timeout=TIMEOUT):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.02)
    return False


def run(args, seconds, record_section):
    """The soak; exit status 0 when every limit holds. Writes its section into args.record if given."""
    load_before = benchlib.load_average()
    master = benchlib.use_new_master()
    launch = None
    problems, rss, cycles, cpu = [], [], 0, None
    try:
        import rospy
        launch = benchlib.roslaunch('ur3_ft_gripper_description', 'ur_ft_gripper_bringup.launch', 'sim:=true',
                                    'ur_type:=ur5e', log=os.environ.get('SOAK_LOG'))
        rospy.init_node('soak_arm', disable_signals=True)
        driver = Driver(rospy)
        pid = benchlib.node_pid(NODE)
        start = time.monotonic()
        warm = None
        while time.monotonic() - start < args.warmup + seconds:
            cycle(driver, cycles, problems)
            cycles += 1
            now = time.monotonic()
            if warm is None and now - start >= args.warmup:
                warm = (now, benchlib.cpu_seconds(pid), cycles, len(problems))
                rss = [benchlib.rss_mb(pid)]
            elif warm is not None:
                rss.append(benchlib.rss_mb(pid))
        if warm is None:
            raise RuntimeError('the run ended within the warm-up: give more time than --warmup')
        cpu = 100.0 * (benchlib.cpu_seconds(pid) - warm[1]) / (time.monotonic() - warm[0])
        measured_cycles = cycles - warm[2]
    finally:
        benchlib.stop(launch)
        benchlib.stop(master)
    growth = max(rss) - rss[0]
    if growth > RSS_LIMIT_MB:
        problems.append('ur_hardware_interface resident memory grew by %.1f MB (limit %g)' % (growth, RSS_LIMIT_MB))
    rows = [
        '| measured | %.0f s after %.0f s warm-up; %d cycles (%d in the warm-up) |' % (
            seconds, args.warmup, measured_cycles, cycles - measured_cycles),
        '| each cycle | scaled trajectory; sec program (IO, 100 textmsg of 1000 characters) and addToLog; movej '
        'program, then play; unscaled trajectory; joint_group_vel 0.5 s; twist 0.5 s; back to the scaled '
        'controller |',
        '| ur_hardware_interface resident memory: after warm-up, max, end, growth | %.1f, %.1f, %.1f MB, +%.2f MB '
        '(limit %g MB) |' % (rss[0], max(rss), rss[-1], growth, RSS_LIMIT_MB),
        '| ur_hardware_interface CPU (500 Hz loop), mean over the measurement | %.0f %% of one core |' % cpu,
        '| goals, programs and switches that failed | %d |' % len(problems),
    ]
    return benchlib.report_soak(
        args.record, record_section, '## Soak of the simulated arm (`bash tools/quickstart soak --what arm`)',
        'ur_ft_gripper_bringup.launch sim:=true ur_type:=ur5e on its own master, driven through '
        'ur_robot_driver\'s interface only.', load_before, rows, problems, 'soak (arm)')
