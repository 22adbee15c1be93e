#!/usr/bin/env python3
"""Soak: the view launch (headless) for a long time, the simulated FT 300 at 100 Hz and
gripper register commands at 10 Hz; checks that the nodes' resident memory does not grow
and the wrench stream has no gap. With --what arm, the simulated arm instead (bench/soak_arm.py);
with --what physics, the cell on physics driven by the shipped examples (bench/soak_physics.py), and with
--wire its FT 300 and 2F-140 also on their serial lines, clients reconnecting every minute (bench/soak_wire.py).

    python3 bench/soak.py [--what devices|arm|physics] [--minutes 30 | --seconds N] [--warmup S] [--record bench/RESULTS.md]

Limits: resident memory of the simulated devices (robotiq_ft_sensor,
robotiq2FGripper, gripper_joint_states) grows by at most 5 MB after the warm-up; no gap over 50 ms between consecutive wrench messages
(header stamps, i.e. as the node published them; the gaps as received here are
reported too); the gripper ends at the last commanded position. Exit status 0
when all hold, 1 otherwise: a measurement, not a test. Started on its own
rosmaster on a free port; `tools/quickstart soak` runs it in the workspace.
"""
import argparse
import math
import os
import sys
import threading
import time

import benchlib  # this folder is the script's, first on sys.path

RSS_LIMIT_MB = 5.0
GAP_LIMIT_S = 0.050
LONG_GAP_S = 0.040  # gaps and stalls longer than this are listed for the diagnosis


class StallWatch(object):
    """This process oversleeping a 5 ms sleep by more than LONG_GAP_S: the machine, not a node, stalled."""

    def __init__(self):
        self.stalls = []  # (woke, overslept)
        threading.Thread(target=self._run, daemon=True).start()

    def _run(self):
        while True:
            before = time.monotonic()
            time.sleep(0.005)
            woke = time.monotonic()
            if woke - before - 0.005 > LONG_GAP_S:
                self.stalls.append((woke, woke - before - 0.005))


def machine_counters():
    """(CPU steal seconds, major page faults) so far, from /proc."""
    with open('/proc/stat') as f:
        steal = int(f.readline().split()[8]) / float(benchlib.CLK_TCK)
    with open('/proc/vmstat') as f:
        faults = next(int(line.split()[1]) for line in f if line.startswith('pgmajfault '))
    return steal, faults


def explained(gaps, *others, slack=0.2):
    """How many of `gaps` overlap an entry of the other lists (same time, +/- slack s)."""
    count = 0
    for t, length in gaps:
        start = t - length - slack
        if any(start <= u <= t + slack for other in others for u, _ in other):
            count += 1
    return count


class Stream(object):
    """Gaps between consecutive messages of one topic: by header stamp and by receipt."""

    def __init__(self):
        self.lock = threading.Lock()
        self.counting = False
        self.count = 0
        self.last = None
        self.max_stamp_gap = self.max_receipt_gap = 0.0
        self.latest = None
        self.long_gaps = []  # (received, stamp gap) of gaps over LONG_GAP_S, for the diagnosis

    def add(self, msg):
        received = time.monotonic()
        stamp = msg.header.stamp.to_sec()
        with self.lock:
            self.latest = msg
            if self.counting and self.last is not None:
                self.count += 1
                self.max_stamp_gap = max(self.max_stamp_gap, stamp - self.last[0])
                if stamp - self.last[0] > LONG_GAP_S:
                    self.long_gaps.append((received, stamp - self.last[0]))
                self.max_receipt_gap = max(self.max_receipt_gap, received - self.last[1])
            self.last = (stamp, received)

    def start_counting(self):
        with self.lock:
            self.counting = True
            self.last = None

    def stop_counting(self):
        with self.lock:
            self.counting = False


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--minutes', type=float, help='measured time after the warm-up (default 30)')
    parser.add_argument('--seconds', type=float, help='the same in seconds (for a short run)')
    parser.add_argument('--warmup', type=float, default=60.0, help='seconds before memory and gaps count')
    parser.add_argument('--record', help='write the numbers into this RESULTS.md (soak section)')
    parser.add_argument('--max-gap-ms', type=float, default=1e3 * GAP_LIMIT_S,
                        help='largest allowed wrench gap (default: the issue\'s %g ms)' % (1e3 * GAP_LIMIT_S))
    parser.add_argument('--real-time-factor', type=float, default=1.0,
                        help='with --what physics: the cell\'s pace on its simulated clock (default 1; 0: as fast '
                             'as the machine allows)')
    parser.add_argument('--wire', action='store_true',
                        help='with --what physics: the FT 300 and the 2F-140 also on their serial lines, read by '
                             'clients that reconnect every --reconnect s (bench/soak_wire.py)')
    parser.add_argument('--reconnect', type=float, default=60.0, help='with --wire: seconds per client session')
    parser.add_argument('--what', choices=('devices', 'arm', 'physics'), default='devices',
                        help='the simulated FT 300 and gripper (default), the simulated arm (bench/soak_arm.py), '
                             'or the cell on physics (bench/soak_physics.py)')
    args = parser.parse_args(argv)
    seconds = args.seconds if args.seconds is not None else 60.0 * (args.minutes or 30.0)
    if args.what == 'arm':
        import soak_arm
        return soak_arm.run(args, seconds, 'soak arm')
    if args.what == 'physics':
        import soak_physics
        return soak_physics.run(args, seconds, 'soak physics wire' if args.wire else 'soak physics')

    master = benchlib.use_new_master()
    launch = None
    try:
        import rospy
        from geometry_msgs.msg import WrenchStamped
        from sensor_msgs.msg import JointState
        from robotiq_2f_gripper_control.msg import (Robotiq2FGripper_robot_input,
                                                    Robotiq2FGripper_robot_output)

        launch = benchlib.roslaunch('ur3_ft_gripper_description', 'view_ur3_ft_gripper.launch',
                                    'gui:=false', 'rviz:=false', log=os.environ.get('SOAK_LOG'))
        rospy.init_node('soak', disable_signals=True)
        wrench, joints = Stream(), Stream()
        rospy.Subscriber('robotiq_ft_wrench', WrenchStamped, wrench.add, queue_size=1000,
                         tcp_nodelay=True)
        rospy.Subscriber('gripper/joint_states', JointState, joints.add, queue_size=1000,
                         tcp_nodelay=True)
        gripper = {}
        rospy.Subscriber('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input,
                         lambda msg: gripper.update(status=msg), queue_size=10)

        def arrived(position):
            s = gripper.get('status')
            return s is not None and s.gPR == position and s.gPO == position and s.gOBJ == 3

        command = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output,
                                  queue_size=10)
        benchlib.wait_for(lambda: wrench.latest and joints.latest and command.get_num_connections(),
                          'the wrench, the gripper\'s joint states and its command subscriber', 60)
        pids = {name: benchlib.node_pid('/' + name)
                for name in ('robotiq_ft_sensor', 'robotiq2FGripper', 'gripper_joint_states')}

        stalls = StallWatch()
        start = time.monotonic()
        rss_at_warmup, rss_max, sent = {}, {}, 0
        target = 0
        rate = rospy.Rate(10)
        while time.monotonic() - start < args.warmup + seconds:
            # A slow sweep of the position register (rACT 1 activates on the first
            # command): the gripper always moves.
            target = int(round(127.5 + 100 * math.sin(2 * math.pi * sent / 100.0)))
            command.publish(Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=target, rSP=255, rFR=150))
            sent += 1
            elapsed = time.monotonic() - start
            if elapsed >= args.warmup and not rss_at_warmup:
                wrench.start_counting()
                joints.start_counting()
                rss_at_warmup = {n: benchlib.rss_mb(p) for n, p in pids.items()}
                counters_at_warmup = machine_counters()
                stalls.stalls = []
                rss_max = dict(rss_at_warmup)
            if rss_at_warmup and sent % 50 == 0:
                for n, p in pids.items():
                    rss_max[n] = max(rss_max[n], benchlib.rss_mb(p))
            rate.sleep()
        wrench.stop_counting()
        joints.stop_counting()
        steal, faults = (b - a for a, b in zip(counters_at_warmup, machine_counters()))
        rss_end = {n: benchlib.rss_mb(p) for n, p in pids.items()}
        for n in pids:
            rss_max[n] = max(rss_max[n], rss_end[n])
        # The last command is reached within 0.56 s (full stroke at rSP 255).
        try:
            status = benchlib.wait_for(lambda: arrived(target), 'the gripper at rPR %d' % target, 10, step=0.01)
        except AssertionError:
            status = None
    finally:
        benchlib.stop(launch)
        benchlib.stop(master)

    growth = {n: rss_max[n] - rss_at_warmup[n] for n in pids}
    problems = []
    for n in pids:
        if growth[n] > RSS_LIMIT_MB:
            problems.append('%s resident memory grew by %.1f MB (limit %g)' % (n, growth[n], RSS_LIMIT_MB))
    gap_limit = args.max_gap_ms / 1e3
    if wrench.max_stamp_gap > gap_limit:
        problems.append('wrench gap %.1f ms (limit %g)' % (1e3 * wrench.max_stamp_gap, 1e3 * gap_limit))
    if not status:
        problems.append('gripper not at the last command rPR %d: %s' % (target, gripper.get('status')))
    measured = seconds
    rows = [
        '| measured | %.0f s after %.0f s warm-up; %d gripper commands at 10 Hz |' % (measured, args.warmup, sent),
        '| wrench messages | %d (%.1f Hz) |' % (wrench.count, wrench.count / measured),
        '| wrench: largest gap, published (stamps) / received | %.1f ms / %.1f ms (limit %g ms) |' % (
            1e3 * wrench.max_stamp_gap, 1e3 * wrench.max_receipt_gap, 1e3 * gap_limit),
        '| gripper/joint_states: largest gap, published / received | %.1f ms / %.1f ms (%.1f Hz) |' % (
            1e3 * joints.max_stamp_gap, 1e3 * joints.max_receipt_gap, joints.count / measured),
    ]
    for n in sorted(pids):
        rows.append('| %s resident memory: after warm-up, max, end, growth | %.1f, %.1f, %.1f MB, +%.2f MB '
                    '(limit %g MB) |' % (n, rss_at_warmup[n], rss_max[n], rss_end[n], growth[n], RSS_LIMIT_MB))
    over = [g for g in wrench.long_gaps if g[1] > gap_limit]
    rows.append('| wrench gaps over the limit / of them while the gripper or this process also stalled | '
                '%d / %d |' % (len(over), explained(over, joints.long_gaps, stalls.stalls)))
    rows.append('| this process oversleeping 5 ms by > %g ms (machine stalls) / longest | %d / %.0f ms |' % (
        1e3 * LONG_GAP_S, len(stalls.stalls), 1e3 * max([d for _, d in stalls.stalls] or [0.0])))
    rows.append('| machine during the measurement: CPU steal, major page faults | %.1f s, %d |' % (steal, faults))
    rows.append('| gripper follows the last command | %s |' % ('yes' if status else 'no'))
    return benchlib.report_soak(
        args.record, 'soak', '## Soak (`bash tools/quickstart soak`)',
        'The view launch (headless, sim:=true) on its own master; ft300_sim at 100 Hz, register commands sweeping '
        'rPR 28..228 at 10 Hz.', load_before, rows, problems, 'soak')


load_before = benchlib.load_average()

if __name__ == '__main__':
    sys.exit(main())
