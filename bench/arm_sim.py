#!/usr/bin/env python3
"""The simulated arm (ur_hardware_interface): state rate at 125 Hz and 500 Hz, and trajectory tracking.

    python3 bench/arm_sim.py [--seconds 10] [--output bench/RESULTS.md]

In the sourced workspace (tools/quickstart shell). For a CB3 (ur3, loop_hz 125)
and an e-Series (ur5e, loop_hz 500), each on its own rosmaster on a free port,
sim_arm.launch with the bare arm's model, then:
- joint_states as received here: rate, gaps (median, p99, max), and the
  node's CPU (user + system over the window);
- tracking: a 4-point trajectory through scaled_pos_joint_traj_controller
  (cubic, with velocities), the controller's own state topic gives desired
  minus actual for every cycle; largest and 99th-percentile error, and how
  far from its goal the arm ends.
Figures, not pass/fail: exit status 0 when every measurement ran.
"""
import sys
import threading
import time

import benchlib  # this folder is the script's, first on sys.path
from ur3_ft_gripper_testing.ur_driver import HOME, JOINTS


def bench(ur_type, seconds, rospy):
    import actionlib
    from control_msgs.msg import FollowJointTrajectoryAction, FollowJointTrajectoryGoal, JointTrajectoryControllerState
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import JointTrajectoryPoint

    if rospy.has_param('/robot_description'):
        rospy.delete_param('/robot_description')
    description = benchlib.roslaunch('ur3_ft_gripper_description', 'load_ur_ft_gripper.launch',
                                     'ur_type:=%s' % ur_type)
    try:
        benchlib.wait_for(lambda: rospy.has_param('/robot_description'), 'the %s model loaded' % ur_type, 60)
    finally:
        benchlib.stop(description)
    launch = benchlib.roslaunch('ur3_ft_gripper_description', 'sim_arm.launch', 'ur_type:=%s' % ur_type)
    try:
        stamps = []
        lock = threading.Lock()

        def on_state(msg):
            with lock:
                stamps.append(time.monotonic())
        sub = rospy.Subscriber('joint_states', JointState, on_state, queue_size=1000, tcp_nodelay=True)
        benchlib.wait_for(lambda: len(stamps) > 10, 'joint_states from ur_hardware_interface', 60)
        found = {}

        def node_pid():
            # The master may still hold the previous run's node for a moment.
            try:
                found['pid'] = benchlib.node_pid('/ur_hardware_interface')
            except (OSError, IOError):
                return False
            return True
        benchlib.wait_for(node_pid, 'the pid of ur_hardware_interface', 30)
        pid = found['pid']
        loop_hz = rospy.get_param('/hardware_control_loop/loop_hz')
        time.sleep(1.0)
        with lock:
            del stamps[:]
        cpu0, t0 = benchlib.cpu_seconds(pid), time.monotonic()
        time.sleep(seconds)
        cpu1, t1 = benchlib.cpu_seconds(pid), time.monotonic()
        with lock:
            window = list(stamps)
        sub.unregister()
        gaps = [(b - a) * 1000.0 for a, b in zip(window, window[1:])]
        rate = {'ur_type': ur_type, 'loop_hz': loop_hz, 'received_hz': len(window) / (t1 - t0),
                'gap_median': benchlib.median(gaps), 'gap_p99': benchlib.percentile(gaps, 99),
                'gap_max': max(gaps), 'cpu': 100.0 * (cpu1 - cpu0) / (t1 - t0)}

        errors = []

        def on_controller_state(msg):
            errors.append(max(abs(e) for e in msg.error.positions))
        client = actionlib.SimpleActionClient('scaled_pos_joint_traj_controller/follow_joint_trajectory',
                                              FollowJointTrajectoryAction)
        if not client.wait_for_server(rospy.Duration(60)):
            raise RuntimeError('no action server scaled_pos_joint_traj_controller/follow_joint_trajectory')
        goal = FollowJointTrajectoryGoal()
        goal.trajectory.joint_names = JOINTS
        for t, offset, speed in ((1.5, 0.4, 0.3), (3.0, 0.7, 0.0), (4.5, 0.3, -0.3), (6.0, 0.0, 0.0)):
            goal.trajectory.points.append(JointTrajectoryPoint(
                positions=[h + offset * (1 if i % 2 else -1) for i, h in enumerate(HOME)],
                velocities=[speed * (1 if i % 2 else -1) for i in range(6)], time_from_start=rospy.Duration(t)))
        state_sub = rospy.Subscriber('scaled_pos_joint_traj_controller/state', JointTrajectoryControllerState,
                                     on_controller_state, queue_size=1000)
        client.send_goal(goal)
        benchlib.wait_for_result(client, 60)
        state_sub.unregister()
        final = rospy.wait_for_message('joint_states', JointState, 10)
        end_error = max(abs(p - h) for p, h in zip(final.position, HOME))
        tracking = {'ur_type': ur_type, 'samples': len(errors), 'max': max(errors),
                    'p99': benchlib.percentile(errors, 99), 'end': end_error,
                    'result': client.get_result().error_code}
        return rate, tracking
    finally:
        benchlib.stop(launch)


def table(results):
    lines = ['### Simulated arm (ur_hardware_interface), %s' % benchlib.now_text(), '',
             'Machine: %s; load average before: %s.' % (benchlib.machine(), benchlib.load_average()), '',
             '| ur_type | loop_hz | joint_states received (Hz) | gap median / p99 / max (ms) | node CPU (%) |',
             '| --- | --- | --- | --- | --- |']
    for rate, _ in results:
        lines.append('| %s | %d | %.1f | %.2f / %.2f / %.2f | %.0f |' % (
            rate['ur_type'], rate['loop_hz'], rate['received_hz'], rate['gap_median'], rate['gap_p99'],
            rate['gap_max'], rate['cpu']))
    lines += ['', 'Tracking, 6 s cubic trajectory through scaled_pos_joint_traj_controller (desired - actual '
              'from its state topic, rad):', '',
              '| ur_type | state samples | max error | p99 error | error at the end | result |',
              '| --- | --- | --- | --- | --- | --- |']
    for _, t in results:
        lines.append('| %s | %d | %.2e | %.2e | %.2e | %d |' % (t['ur_type'], t['samples'], t['max'], t['p99'],
                                                               t['end'], t['result']))
    return '\n'.join(lines) + '\n'


def main(argv=None):
    return benchlib.main_per_ur_type(argv, __doc__, __file__, 'arm_sim', bench, table, 10.0)


if __name__ == '__main__':
    sys.exit(main())
