#!/usr/bin/env python3
"""rostest node: the simulated cell on one clock (sim_clock.test), judged on simulated time.

At real_time_factor 0 the cell runs as fast as the machine allows; nothing
of what the drivers' interfaces publish may be lost or repeated for it:
rq_sensor's stream carries one reading per 10 ms of simulated time, stamped
with it; joint_state_controller one joint state per control period; the
2F-140 one status per 20 ms; and the FT 300's data stream on its serial line
(rq_sensor's start, frames as its manual lays them out) one frame per
reading, the same values as the topic's message of that reading. The real-time factor the arm's node reports is
checked against what /clock and this process's wall clock show over the
same window, and /clock's own steps against the rate the launch asked for
(every control period, or pub_clock_frequency's stride).

Throughout the window, bad programs arrive on script_command: seeded mutants
of the URScript corpus (ur3_ft_gripper_testing.urscript_mutants), one every
50 ms of simulated time, as a buggy generator would send them. Every joint
state must still come, one per period: a bad program never stops the node.
After them a program still runs, and the node refused the ones that do not
compile, each on one line.
"""
import bisect
import os
import struct
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import WrenchStamped
from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input
from rosgraph_msgs.msg import Clock
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import JointState
from std_msgs.msg import String

from ur3_ft_gripper_testing import rostest_helpers, urscript_mutants
from ur3_ft_gripper_testing.modbus_frames import valid_crc
from ur3_ft_gripper_testing.ur_driver import HW

# Ten simulated seconds of each stream, counted from a start well after the cell came up.
SPAN = 10.0
FT_PERIOD = 0.01       # rq_sensor's 100 Hz
GRIPPER_PERIOD = 0.02  # the Robotiq driver's 50 Hz status
# How far apart (simulated s) the two halves of the window may put the status ticks: three ticks. A node
# that lost or repeated three ticks, or ran at 51 Hz, puts them further apart.
GRIPPER_DRIFT = 3 * GRIPPER_PERIOD
# Each half's tick time is the lower quartile of its (receipt - k T). Receipts are late by this node's
# lags, which are near zero for most statuses; and early when this node's other streams' threads have not
# yet drained what came while it was held back (a busy machine): their newest time is then stale, by
# 82 ms for five statuses once, with two whole test runs side by side. A quartile stands both.
QUANTILE = 0.25
# Statuses in each half below which no quartile is judged.
FEWEST = 50
# The halves reach this far (simulated s) before and after the window: the longer a half, the more
# statuses its quartile stands on.
GRIPPER_REACH = 5.0
# Reports of the real-time factor to check against /clock.
REPORTS = 5
# Stamps are whole nanoseconds: two readings a period apart differ by it to within a nanosecond.
STAMP_TOLERANCE = 2e-9
# Bad programs sent through the window: one per BAD_PROGRAM_PERIOD simulated seconds.
BAD_PROGRAM_SEED = 7
BAD_PROGRAM_PERIOD = 0.05
ARM_NODE = '/ur_hardware_interface'


def primary_mutants(count):
    """`count` seeded mutants that are primary programs (or bare statements): each replaces the last, as on
    the robot. Secondary ones would pile up beside it, which is a different test."""
    programs = [(name, text) for name, text in urscript_mutants.corpus() if not text.lstrip().startswith('sec')]
    made = urscript_mutants.mutants(BAD_PROGRAM_SEED, 3 * count, programs, urscript_mutants.function_names())
    return [text for _, text in made if not text.lstrip().startswith('sec')][:count]


class BadPrograms(object):
    """Sends mutants on script_command, one every BAD_PROGRAM_PERIOD of simulated time through `span` s.

    The mutants are made before the window is placed (send_from): making them takes this process's
    Python for a while, and inside the window that would hold back its subscribers' threads, each
    draining its backlog in its own order afterwards, which made statuses look early.
    """

    def __init__(self, span):
        self.publisher = rospy.Publisher(HW + 'script_command', String, queue_size=100)
        rostest_helpers.wait_for_subscribers(self.publisher)
        self.programs = primary_mutants(int(round(span / BAD_PROGRAM_PERIOD)))
        self.sent = 0
        self.start = None
        self.thread = threading.Thread(target=self._send, daemon=True)

    def send_from(self, start):
        self.start = start
        self.thread.start()

    def _send(self):
        for index, text in enumerate(self.programs):
            when = self.start + index * BAD_PROGRAM_PERIOD
            while rospy.get_time() < when and not rospy.is_shutdown():
                time.sleep(0.002)
            self.publisher.publish(String(data=text))
            self.sent += 1


class Streams(object):
    """Every message of the four streams: the stamps, the gripper's statuses' simulated times of receipt, and
    /clock's and the diagnostics' wall-clock times of receipt."""

    def __init__(self):
        self.lock = threading.Lock()
        self.clock, self.arm, self.wrench, self.gripper, self.diagnostics = [], [], [], [], []
        self.wrench_counts = []  # (stamp, the reading in the stream's counts)
        # The newest simulated time (s) any stream has shown this node: a status's time of receipt. Not
        # rospy.get_time() alone: its /clock can fall behind the other streams' threads, by 0.3 s once
        # at 500 Hz beside four busy processes, and make statuses look early.
        self.newest = 0.0
        # queue_size None: rospy keeps every message for the callback, however late this node runs.
        rospy.Subscriber('/clock', Clock, self._on_clock, queue_size=None)
        rospy.Subscriber('joint_states', JointState, self._on_joints, queue_size=None)
        rospy.Subscriber('robotiq_ft_wrench', WrenchStamped, self._on_wrench, queue_size=None)
        rospy.Subscriber('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input, self._on_gripper,
                         queue_size=None)
        rospy.Subscriber('/diagnostics', DiagnosticArray, self._on_diagnostics, queue_size=None)

    def _on_clock(self, msg):
        with self.lock:
            self.clock.append((time.monotonic(), msg.clock.to_sec()))
            self.newest = max(self.newest, msg.clock.to_sec())

    def _on_joints(self, msg):
        if 'shoulder_pan_joint' in msg.name:
            with self.lock:
                self.arm.append(msg.header.stamp.to_nsec())
                self.newest = max(self.newest, msg.header.stamp.to_sec())

    def _on_wrench(self, msg):
        force, torque = msg.wrench.force, msg.wrench.torque
        counts = (round(force.x * 100), round(force.y * 100), round(force.z * 100), round(torque.x * 1000),
                  round(torque.y * 1000), round(torque.z * 1000))  # the stream's 0.01 N and 0.001 N m
        with self.lock:
            self.wrench.append(msg.header.stamp.to_nsec())
            self.wrench_counts.append((msg.header.stamp.to_nsec(), counts))
            self.newest = max(self.newest, msg.header.stamp.to_sec())

    def _on_gripper(self, msg):
        with self.lock:
            self.newest = max(self.newest, rospy.get_time())
            self.gripper.append(self.newest)

    def factors_beside_clock(self):
        """(reported, measured) for each report of the real-time factor with a whole window of /clock beside
        it: the node's factor is over the last 3 wall-clock s before it reports; measured is the same window
        from this node's records of /clock, taken when each arrives. A busy machine leaves some reports
        without one (this node's /clock came late), so the test waits for enough that have one."""
        with self.lock:
            reports = list(self.diagnostics)
            clock = list(self.clock)
        walls = [w for w, _ in clock]  # in order of arrival: sorted
        pairs = []
        for wall, reported in reports[2:]:
            first, end = bisect.bisect_left(walls, wall - 3.0), bisect.bisect_right(walls, wall)
            if end - first < 100 or walls[first] > wall - 2.9:
                continue
            (w0, c0), (w1, c1) = clock[first], clock[end - 1]
            pairs.append((reported, (c1 - c0) / (w1 - w0)))
        return pairs

    def _on_diagnostics(self, msg):
        for status in msg.status:
            values = {v.key: v.value for v in status.values}
            if status.name.endswith(': physics') and values.get('real-time factor'):
                with self.lock:
                    self.diagnostics.append((time.monotonic(), float(values['real-time factor'])))


class SerialStream(object):
    """The FT 300's data stream on its serial line, as rq_sensor starts it and reads it: every byte, kept by a
    thread of its own until stop()."""

    START = bytes.fromhex('09 10 01 9A 00 01 02 02 00 CD CA')  # rq_sensor's write of 0x0200 to register 410
    STARTED = bytes.fromhex('09 10 01 9A 00 01 21 52')

    def __init__(self, path):
        import serial
        rostest_helpers.wait_for(lambda: os.path.exists(path), 'the FT 300 serial port at %s' % path)
        self.port = serial.Serial(path, 19200, timeout=rostest_helpers.TIMEOUT)
        self.port.write(self.START)
        self.echo = self.port.read(len(self.STARTED))
        self.port.timeout = 0.05
        self.data = bytearray()
        self.stopping = threading.Event()
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self):
        while not self.stopping.is_set():
            self.data += self.port.read(4096)

    def stop(self):
        self.stopping.set()
        self.thread.join()
        self.port.write(b'\xff' * 50)
        self.port.close()

    def frames(self):
        """[(counts, CRC valid)] of the whole frames read: 0x20 0x4E, six int16 least significant byte first, and
        the CRC-16 of the Modbus specification, least significant byte first."""
        frames = []
        for start in range(0, len(self.data) - 15, 16):
            frame = bytes(self.data[start:start + 16])
            frames.append((struct.unpack('<6h', frame[2:14]), frame[:2] == b'\x20\x4e' and valid_crc(frame)))
        return frames


def in_window(stamps_ns, start_ns, end_ns):
    return [s for s in stamps_ns if start_ns <= s < end_ns]


class SimClockTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('sim_clock_check')
        cls.loop_hz = float(rospy.get_param('~loop_hz'))
        cls.clock_step_ns = int(round(float(rospy.get_param('~clock_step')) * 1e9))
        cls.streams = Streams()
        # The cell is up once every stream flows; counting starts a simulated second later.
        rostest_helpers.wait_for(lambda: cls.streams.arm and cls.streams.wrench and cls.streams.gripper,
                                 'joint_states, robotiq_ft_wrench and Robotiq2FGripperRobotInput')
        cls.rosout = rostest_helpers.Recorder('/rosout', Log)
        cls.stream = SerialStream(rospy.get_param('~ft_serial_port'))
        cls.bad_programs = BadPrograms(SPAN)
        # A simulated second for the subscribers' threads to drain what came while the mutants were made.
        rospy.sleep(1.0)
        # Whole nanoseconds on a multiple of every period (2, 8, 10, 20 ms), so that a window of SPAN holds
        # exactly SPAN / period stamps of each stream.
        grid = 40000000
        cls.start_ns = (int(rospy.get_time() * 1e9 + GRIPPER_REACH * 1e9) // grid + 25) * grid
        cls.end_ns = cls.start_ns + int(SPAN * 1e9)
        cls.start, cls.end = cls.start_ns * 1e-9, cls.end_ns * 1e-9
        cls.bad_programs.send_from(cls.start)
        # Waits on simulated time: the window is over when /clock has passed its end by a second.
        after = GRIPPER_REACH + 1.0
        rostest_helpers.wait_for(lambda: rospy.get_time() > cls.end + after, 'the end of the windows on /clock',
                                 timeout=rostest_helpers.TIMEOUT + 60)
        cls.stream.stop()
        # The factor is reported once a wall-clock second, over the last three: enough reports to check.
        rostest_helpers.wait_for(lambda: len(cls.streams.factors_beside_clock()) >= REPORTS,
                                 '%d reports of the real-time factor on /diagnostics with /clock beside them'
                                 % REPORTS)

    def test_the_ft300_stream_has_one_reading_per_10_ms_of_simulated_time(self):
        stamps = in_window(self.streams.wrench, self.start_ns, self.end_ns)
        self.assertEqual(len(stamps), round(SPAN / FT_PERIOD), 'readings in %g simulated s' % SPAN)
        gaps = {round((b - a) * 1e-9, 9) for a, b in zip(stamps, stamps[1:])}
        self.assertEqual(gaps, {FT_PERIOD}, 'the gaps between consecutive stamps (s)')

    def test_the_serial_stream_carries_each_reading_of_the_window_frame_for_message(self):
        self.assertEqual(self.stream.echo, SerialStream.STARTED)
        frames = self.stream.frames()
        self.assertTrue(all(valid for _, valid in frames), 'frames with a bad header or CRC')
        with self.streams.lock:
            published = sorted(self.streams.wrench_counts)
        values = [counts for _, counts in published]
        first = values.index(frames[0][0])  # the readings carry the sensor's noise: each is its own
        streamed = [counts for counts, _ in frames]
        self.assertEqual(values[first:first + len(streamed)], streamed, 'the frames against the messages')
        stamps = [stamp for stamp, _ in published[first:first + len(streamed)]]
        # Every reading of the window went out as a frame: 1,000 in 10 simulated seconds.
        self.assertEqual(len(in_window(stamps, self.start_ns, self.end_ns)), round(SPAN / FT_PERIOD))

    def test_ros_time_moves_in_the_steps_of_the_clock_rate_asked(self):
        with self.streams.lock:
            ticks = [int(round(c * 1e9)) for _, c in self.streams.clock if self.start <= c < self.end]
        # rospy drops the oldest /clock messages of a subscriber that falls behind, so some gaps may span
        # several steps; none is shorter, and every tick is on the step's grid.
        self.assertGreater(len(ticks), 100)
        self.assertEqual({t % self.clock_step_ns for t in ticks}, {0}, 'ticks off a %d ns grid' % self.clock_step_ns)
        self.assertEqual(min(b - a for a, b in zip(ticks, ticks[1:])), self.clock_step_ns, 'the shortest step (ns)')

    def test_joint_states_come_once_per_control_period(self):
        period = 1.0 / self.loop_hz
        stamps = in_window(self.streams.arm, self.start_ns, self.end_ns)
        self.assertEqual(len(stamps), round(SPAN / period), 'joint states in %g simulated s' % SPAN)
        gaps = {round((b - a) * 1e-9, 9) for a, b in zip(stamps, stamps[1:])}
        self.assertEqual(gaps, {round(period, 9)}, 'the gaps between consecutive stamps (s)')

    def test_the_gripper_status_comes_at_50_hz_of_simulated_time(self):
        with self.streams.lock:
            received = [t for t in self.streams.gripper
                        if self.start - GRIPPER_REACH <= t < self.end + GRIPPER_REACH]
        # Received, not stamped (the register message has no header), and a node running late serves the
        # ticks it missed at once. So a count of receipts in the window is off by the lags at its two
        # edges: 484 to 556 of 500, in windows a few tenths of a second apart, beside four busy
        # processes. Status k was ticked at k T + c, and received later by a lag that is near zero for
        # most statuses, even on a busy machine: the lower quartile of (receipt - k T) in each half of the
        # window, reaching out of it by GRIPPER_REACH, is c. A node that loses, repeats or mistimes ticks
        # between the halves moves c.
        middle = (self.start + self.end) / 2.0
        halves = ([], [])
        for k, received_at in enumerate(received):
            # Statuses are a period apart: one taken less than half a period after the one before came out
            # of a backlog drained at once, its receipt no measure of its tick.
            if k and received_at - received[k - 1] < GRIPPER_PERIOD / 2:
                continue
            halves[received_at >= middle].append(received_at - k * GRIPPER_PERIOD)
        counts = [len(half) for half in halves]
        self.assertTrue(all(count >= FEWEST for count in counts), 'statuses in each half: %s' % counts)
        first, second = (sorted(half)[int(len(half) * QUANTILE)] for half in halves)
        rospy.loginfo('sim_clock_check: status ticks at %.4f and %.4f s into the window, %s statuses'
                      % (first - self.start, second - self.start, counts))
        self.assertAlmostEqual(second, first, delta=GRIPPER_DRIFT, msg=(
            'ticks at %.3f s in the first half of the window, %.3f s in the second (%s statuses)' % (
                first - self.start, second - self.start, counts)))

    def test_the_reported_real_time_factor_is_what_clock_and_the_wall_clock_show(self):
        pairs = self.streams.factors_beside_clock()
        self.assertGreaterEqual(len(pairs), REPORTS, 'diagnostics with a whole window of /clock beside them')
        # The median of the ratios: this node's arrival times of /clock are off by its lags at a window's
        # two edges, 12 % once over 3 s on a busy machine, while a node that reports a wrong factor is off
        # in every window.
        ratios = sorted(reported / measured for reported, measured in pairs)
        self.assertAlmostEqual(ratios[len(ratios) // 2], 1.0, delta=0.1, msg=(
            'reported over measured factors: %s' % ', '.join('%.3f' % r for r in ratios)))
        rospy.loginfo('sim_clock_check: /clock ran at %.2f x the wall clock (real_time_factor 0, %g Hz)'
                      % (pairs[-1][1], self.loop_hz))

    def test_after_the_bad_programs_a_program_runs_and_each_refusal_was_one_line(self):
        self.bad_programs.thread.join(rostest_helpers.TIMEOUT)
        self.assertEqual(self.bad_programs.sent, len(self.bad_programs.programs))
        # A secondary program: it runs even where a mutant left the arm protectively stopped.
        since = time.monotonic()
        self.bad_programs.publisher.publish(String(data='sec after():\n  textmsg("after the bad programs")\nend'))
        rostest_helpers.wait_for_log(self.rosout, ARM_NODE, Log.INFO, 'robot log: after the bad programs',
                                     since=since)
        refusals = rostest_helpers.logs(self.rosout, ARM_NODE, Log.ERROR, 'would not compile')
        self.assertGreater(len(refusals), 0)
        self.assertTrue(all('\n' not in text and 'line ' in text for text in refusals), refusals)
        rospy.loginfo('sim_clock_check: %d bad programs sent, %d refused' % (self.bad_programs.sent, len(refusals)))


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'sim_clock', SimClockTest)
