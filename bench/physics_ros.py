#!/usr/bin/env python3
"""The physics cell behind the ROS interfaces at their real rates, on its simulated clock at 1x and at full speed.

    python3 bench/physics_ros.py [--seconds 20] [--output bench/RESULTS.md]

In the sourced workspace (tools/quickstart shell), with MuJoCo installed. For a CB3 (ur3, 125 Hz) and an
e-Series (ur5e, 500 Hz), each at real_time_factor 1 and 0 (as fast as the machine allows), and the ur5e
again with /clock at 100 Hz (pub_clock_frequency:=100, as Gazebo users set theirs; the default is every cycle),
each on its own rosmaster on a free port, the bring-up with sim:=true physics:=true in the default world, then for
`seconds` of wall-clock time, while the arm runs a trajectory through scaled_pos_joint_traj_controller
back and forth and the gripper closes and opens through its registers:
- /clock over the wall clock (the real-time factor achieved, measured here), and the factor the arm's
  node reports on /diagnostics (mean and lowest over the window);
- as received here, per simulated second: joint_states (the arm's control rate), robotiq_ft_wrench
  (100 Hz) and Robotiq2FGripperRobotInput (50 Hz), and the largest gap between consecutive stamps
  (simulated ms; the gripper's status has no stamp);
- CPU of the arm's process (the cell steps there), also per control cycle, and of the FT 300's and the
  gripper's nodes;
- in the same process just before, the cell alone (no ROS, no controller): its real-time factor on CPU
  time over the same back-and-forth motion at the ur_type's control period with the fingers closing and
  opening, so that /clock over the wall clock reads as a share of what the physics allows.
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
    """(wall-clock receipt, stamp or None) of a stream's messages."""

    def __init__(self, stamped):
        self.lock = threading.Lock()
        self.items = []
        self.stamped = stamped

    def add(self, msg):
        stamp = msg.header.stamp.to_sec() if self.stamped else None
        with self.lock:
            self.items.append((time.monotonic(), stamp))

    def window(self, start, end, simulated):
        """Messages per simulated second over the wall-clock window, and the largest stamp gap (ms)."""
        with self.lock:
            items = [(t, s) for t, s in self.items if start <= t <= end]
        stamps = [s for _, s in items if s is not None]
        gaps = [(b - a) * 1e3 for a, b in zip(stamps, stamps[1:])]
        return dict(hz=len(items) / simulated, max_gap=max(gaps) if gaps else float('nan'))


PERIOD = {'ur3': 0.008, 'ur5e': 0.002}  # s: a CB3's and an e-Series' control period


def cell_alone(ur_type, seconds):
    """The cell's real-time factor on CPU time, stepped by the arm's joint motion at `ur_type`'s control
    period over `seconds` of simulated time: the bench's own 2 s moves between HOME and AWAY (a quintic,
    as the trajectory controller streams them), the fingers closing and opening with each move."""
    import numpy as np
    from ur3_ft_gripper_description.devices.physics.arm_cell import default_world_file
    from ur3_ft_gripper_description.devices.physics.cell import Cell
    from ur3_ft_gripper_description.devices.physics.world import load_world
    from ur3_ft_gripper_description.devices.ur_arm.joints import JointCommand
    from ur3_ft_gripper_description.devices.ur_arm.physics_joints import PhysicsJointMotion
    from ur3_ft_gripper_description.model import description, export
    # As the arm's node builds it (physics/arm_cell.py): the model as loaded, the default world, HOME.
    urdf = description.to_xml(description.expand_model(export.model_mappings(ur_type=ur_type)))
    cell = Cell.from_description(urdf, ur_type, '', load_world(default_world_file()), HOME)
    motion = PhysicsJointMotion(cell)
    dt, home, away = PERIOD[ur_type], np.array(HOME), np.array(AWAY)
    per_move = int(round(2.0 / dt))
    start_time, start_cpu = cell.time, time.process_time()
    for k in range(int(round(seconds / dt))):
        move, step = divmod(k, per_move)
        origin, target = (home, away) if move % 2 == 0 else (away, home)
        if step == 0:
            cell.command_finger(0.0 if move % 2 == 0 else 0.14, 0.075, 125.0)
        s = (step + 1) / float(per_move)
        blend = 10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5
        rate = (30 * s ** 2 - 60 * s ** 3 + 30 * s ** 4) / 2.0
        motion.step(JointCommand('SERVO', origin + (target - origin) * blend, (target - origin) * rate), dt)
    return (cell.time - start_time) / (time.process_time() - start_cpu)


def bench(case, seconds, rospy):
    """`case`: 'UR_TYPE:FACTOR' or 'UR_TYPE:FACTOR:PUB_CLOCK_FREQUENCY'."""
    ur_type, factor, clock_hz = (case.split(':') + ['0'])[:3]
    alone = cell_alone(ur_type, 20.0)
    import actionlib
    from control_msgs.msg import FollowJointTrajectoryAction, FollowJointTrajectoryGoal
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import WrenchStamped
    from rosgraph_msgs.msg import Clock
    from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input, Robotiq2FGripper_robot_output
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import JointTrajectoryPoint

    launch = benchlib.roslaunch('ur3_ft_gripper_description', 'ur_ft_gripper_bringup.launch', 'sim:=true',
                                'physics:=true', 'ur_type:=%s' % ur_type, 'real_time_factor:=%s' % factor,
                                'pub_clock_frequency:=%s' % clock_hz,
                                log=os.environ.get('BENCH_LOG'))
    try:
        streams = {'joint_states': Arrivals(True), 'robotiq_ft_wrench': Arrivals(True),
                   'Robotiq2FGripperRobotInput': Arrivals(False)}
        clock = []
        rospy.Subscriber('/clock', Clock, lambda msg: clock.append((time.monotonic(), msg.clock.to_sec())),
                         queue_size=1000, tcp_nodelay=True)
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
        benchlib.wait_for(lambda: all(s.items for s in streams.values()) and gripper.get_num_connections(),
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
        ticks = [c for t, c in clock if start <= t <= end]
        simulated = ticks[-1] - ticks[0]
        return dict(ur_type=ur_type, factor=float(factor), clock_hz=float(clock_hz), loop_hz=rospy.get_param('/hardware_control_loop/loop_hz'),
                    moves=moves, seconds=end - start, clock_factor=simulated / (end - start),
                    streams={k: s.window(start, end, simulated) for k, s in streams.items()},
                    rtf_mean=sum(window) / len(window) if window else float('nan'),
                    rtf_min=min(window) if window else float('nan'), cpu=cpu, alone=alone,
                    cycle_us=1e6 * cpu['/ur_hardware_interface'] / 100.0 * (end - start)
                    / (simulated * rospy.get_param('/hardware_control_loop/loop_hz')))
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
             'world, on its simulated clock paced at real_time_factor 1 and 0 (as fast as possible); a 2 s '
             'trajectory back and forth through scaled_pos_joint_traj_controller and the gripper closing and '
             'opening at rSP 128 all along. Rates are per simulated second; gaps between stamps in simulated ms.'
             % (benchlib.machine(), benchlib.load_average()), '',
             '| ur_type | real_time_factor | /clock (Hz simulated) | /clock over wall clock | the cell alone (CPU) | '
             'share | reported mean / lowest | topic | per simulated s | largest stamp gap (ms) |',
             '| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |']
    for r in results:
        for k, (topic, s) in enumerate(sorted(r['streams'].items())):
            head = ('| %s | %g | %s | %.2f | %.1f | %.2f | %.2f / %.2f ' % (
                r['ur_type'], r['factor'], _clock_rate(r), r['clock_factor'], r['alone'],
                r['clock_factor'] / r['alone'], r['rtf_mean'], r['rtf_min']) if k == 0 else '| | | | | | | ')
            lines.append(head + '| %s | %.1f | %.1f |' % (topic, s['hz'], s['max_gap']))
    lines += ['', '| ur_type | real_time_factor | /clock (Hz simulated) | measured (wall s) | trajectories | '
              'CPU (% of one core): '
              'ur_hardware_interface (arm + cell) | its CPU per control cycle (us) | robotiq_ft_sensor | '
              'robotiq2FGripper |', '| --- | --- | --- | --- | --- | --- | --- | --- | --- |']
    for r in results:
        lines.append('| %s | %g | %s | %.0f | %d | %.0f | %.0f | %.0f | %.0f |' % (
            r['ur_type'], r['factor'], _clock_rate(r), r['seconds'], r['moves'], r['cpu']['/ur_hardware_interface'],
            r['cycle_us'], r['cpu']['/robotiq_ft_sensor'], r['cpu']['/robotiq2FGripper']))
    return '\n'.join(lines) + '\n'


def _clock_rate(result):
    """/clock's rate: every control cycle (the default), or pub_clock_frequency's."""
    return '%g (every cycle)' % result['loop_hz'] if not result['clock_hz'] else '%g' % result['clock_hz']


def main(argv=None):
    return benchlib.main_per_ur_type(argv, __doc__, __file__, 'physics_ros', bench, table, 20.0,
                                     cases=('ur3:1', 'ur3:0', 'ur5e:1', 'ur5e:0', 'ur5e:1:100', 'ur5e:0:100'))


if __name__ == '__main__':
    sys.exit(main())
