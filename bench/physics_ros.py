#!/usr/bin/env python3
"""The physics cell behind the ROS interfaces at their real rates: real-time factor, state rates, gaps, CPU.

    python3 bench/physics_ros.py [--seconds 20] [--output bench/RESULTS.md]

In the sourced workspace (tools/quickstart shell), with MuJoCo installed. For a CB3 (ur3, 125 Hz) and an
e-Series (ur5e, 500 Hz), each on its own rosmaster on a free port, the bring-up with sim:=true
physics:=true in the default world, then for `seconds`, while the arm runs a trajectory through
scaled_pos_joint_traj_controller back and forth and the gripper closes and opens through its registers:
- as received here: joint_states (the arm's control rate), robotiq_ft_wrench (100 Hz) and
  Robotiq2FGripperRobotInput (50 Hz): rate, gaps (median, p99, max);
- the real-time factor the arm's node reports on /diagnostics (mean and lowest over the window);
- CPU of the arm's process (the cell steps there), and of the FT 300's and the gripper's nodes.
Figures, not pass/fail: exit status 0 when every measurement ran.
"""
import os
import sys
import threading
import time

import benchlib  # this folder is the script's, first on sys.path

HOME = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]
AWAY = [0.5, -1.4, 1.4, -1.5708, -1.5708, 0.5]
NODES = ('/ur_hardware_interface', '/robotiq_ft_sensor', '/robotiq2FGripper')



class Arrivals(object):
    def __init__(self):
        self.lock = threading.Lock()
        self.times = []

    def add(self, _msg):
        with self.lock:
            self.times.append(time.monotonic())

    def window(self, start, end):
        with self.lock:
            times = [t for t in self.times if start <= t <= end]
        gaps = [(b - a) * 1e3 for a, b in zip(times, times[1:])]
        return dict(hz=len(times) / (end - start), median=benchlib.median(gaps), p99=benchlib.percentile(gaps, 99),
                    max=max(gaps) if gaps else float('nan'))


def bench(ur_type, seconds, rospy):
    import actionlib
    from control_msgs.msg import FollowJointTrajectoryAction, FollowJointTrajectoryGoal
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import WrenchStamped
    from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input, Robotiq2FGripper_robot_output
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import JointTrajectoryPoint

    launch = benchlib.roslaunch('ur3_ft_gripper_description', 'ur_ft_gripper_bringup.launch', 'sim:=true',
                                'physics:=true', 'ur_type:=%s' % ur_type, log=os.environ.get('BENCH_LOG'))
    try:
        streams = {name: Arrivals() for name in ('joint_states', 'robotiq_ft_wrench', 'Robotiq2FGripperRobotInput')}
        rospy.Subscriber('joint_states', JointState,
                         lambda msg: streams['joint_states'].add(msg) if len(msg.name) == 6 else None,
                         queue_size=1000, tcp_nodelay=True)
        rospy.Subscriber('robotiq_ft_wrench', WrenchStamped, streams['robotiq_ft_wrench'].add, queue_size=1000,
                         tcp_nodelay=True)
        rospy.Subscriber('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input,
                         streams['Robotiq2FGripperRobotInput'].add, queue_size=1000, tcp_nodelay=True)
        factors = []
        rospy.Subscriber('/diagnostics', DiagnosticArray, lambda msg: factors.extend(
            (time.monotonic(), float(v.value)) for s in msg.status for v in s.values
            if v.key == 'real-time factor' and v.value), queue_size=100)
        gripper = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output, queue_size=10)
        client = actionlib.SimpleActionClient('scaled_pos_joint_traj_controller/follow_joint_trajectory',
                                              FollowJointTrajectoryAction)
        if not client.wait_for_server(rospy.Duration(120)):
            raise RuntimeError('no scaled_pos_joint_traj_controller action server')
        benchlib.wait_for(lambda: all(s.times for s in streams.values()) and gripper.get_num_connections(),
                          'the three state streams and the gripper command subscriber', 120)
        pids = {}
        for node in NODES:
            pids[node] = benchlib.wait_for(lambda: _pid(node), 'the pid of %s' % node, 30)
        gripper.publish(Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=0, rSP=255, rFR=150))
        time.sleep(3.0)
        cpu0 = {n: benchlib.cpu_seconds(p) for n, p in pids.items()}
        start = time.monotonic()
        moves = 0
        while time.monotonic() - start < seconds:
            goal = FollowJointTrajectoryGoal()
            goal.trajectory.joint_names = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint',
                                           'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint']
            target = AWAY if moves % 2 == 0 else HOME
            goal.trajectory.points.append(JointTrajectoryPoint(positions=target, velocities=[0.0] * 6,
                                                               time_from_start=rospy.Duration(2.0)))
            gripper.publish(Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=255 if moves % 2 == 0 else 0,
                                                          rSP=128, rFR=150))
            client.send_goal(goal)
            client.wait_for_result(rospy.Duration(30))
            moves += 1
        end = time.monotonic()
        cpu = {n: 100.0 * (benchlib.cpu_seconds(p) - cpu0[n]) / (end - start) for n, p in pids.items()}
        window = [f for t, f in factors if start <= t <= end]
        return dict(ur_type=ur_type, loop_hz=rospy.get_param('/hardware_control_loop/loop_hz'), moves=moves,
                    seconds=end - start, streams={k: s.window(start, end) for k, s in streams.items()},
                    rtf_mean=sum(window) / len(window) if window else float('nan'),
                    rtf_min=min(window) if window else float('nan'), cpu=cpu)
    finally:
        benchlib.stop(launch)


def _pid(node):
    try:
        return benchlib.node_pid(node)
    except (OSError, IOError):
        return None


def table(results):
    lines = ['### Physics cell behind the ROS interfaces (`bench/physics_ros.py`), %s' % benchlib.now_text(), '',
             'Machine: %s; load average before: %s. The bring-up with sim:=true physics:=true in the default '
             'world; a 2 s trajectory back and forth through scaled_pos_joint_traj_controller and the gripper '
             'closing and opening at rSP 128 all along.' % (benchlib.machine(), benchlib.load_average()), '',
             '| ur_type | loop_hz | real-time factor mean / lowest | topic | received (Hz) | gap median / p99 / max (ms) |',
             '| --- | --- | --- | --- | --- | --- |']
    for r in results:
        for k, (topic, s) in enumerate(sorted(r['streams'].items())):
            head = ('| %s | %d | %.3f / %.3f ' % (r['ur_type'], r['loop_hz'], r['rtf_mean'], r['rtf_min'])
                    if k == 0 else '| | | ')
            lines.append(head + '| %s | %.1f | %.2f / %.2f / %.2f |' % (topic, s['hz'], s['median'], s['p99'], s['max']))
    lines += ['', '| ur_type | measured (s) | trajectories | CPU (% of one core): ur_hardware_interface (arm + cell) '
              '| robotiq_ft_sensor | robotiq2FGripper |', '| --- | --- | --- | --- | --- | --- |']
    for r in results:
        lines.append('| %s | %.0f | %d | %.0f | %.0f | %.0f |' % (
            r['ur_type'], r['seconds'], r['moves'], r['cpu']['/ur_hardware_interface'], r['cpu']['/robotiq_ft_sensor'],
            r['cpu']['/robotiq2FGripper']))
    return '\n'.join(lines) + '\n'


def main(argv=None):
    return benchlib.main_per_ur_type(argv, __doc__, __file__, 'physics_ros', bench, table, 20.0)


if __name__ == '__main__':
    sys.exit(main())
