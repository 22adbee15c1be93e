"""The devices on the wire during a soak (bench/soak.py --what physics --wire): clients that come and go.

- The FT 300's serial line: a session every `every` s (wall clock), as rq_sensor runs one: open the port,
  start the stream (0x0200 to register 410), read, stop it with 0xFF bytes, read until the line is quiet,
  close. Each session's frames must be valid and be the topic's messages, one for one and in order, each
  plus the zero rq_sensor's driver held then (the device streams its own readings; the examples zero the
  sensor every cycle): a lost, repeated or changed frame shows as a mismatch.
- The 2F-140's serial line: a Modbus RTU client reading the status at 10 Hz as Robotiq's node does,
  reconnecting every `every` s; every read must be answered.
"""
import os
import struct
import threading
import time

import benchlib
from ur3_ft_gripper_testing.modbus_frames import crc_framed, valid_crc

START_STREAM = bytes.fromhex('09 10 01 9A 00 01 02 02 00 CD CA')
STARTED = bytes.fromhex('09 10 01 9A 00 01 21 52')
STOP_STREAM = b'\xff' * 50
READ_STATUS = crc_framed(bytes.fromhex('09 03 07 D0 00 03'))
STATUS_REPLY = 11  # slave, function, byte count, three registers, CRC
FRAME = 16
# The examples zero the sensor at most once in this many readings (half a second of the cell's time): a
# stretch of frames with one zero shorter than this, inside a session, is a frame that is not the topic's.
LEAST_BETWEEN_ZEROS = 50


def counts(msg):
    """A robotiq_ft_wrench message in the stream's counts (0.01 N, 0.001 N m)."""
    force, torque = msg.wrench.force, msg.wrench.torque
    return (round(force.x * 100), round(force.y * 100), round(force.z * 100), round(torque.x * 1000),
            round(torque.y * 1000), round(torque.z * 1000))


class WireClients(object):
    def __init__(self, sensor_path, gripper_path, every):
        self.sensor_path, self.gripper_path, self.every = sensor_path, gripper_path, every
        self.stopping = threading.Event()
        self.sessions = []  # per FT 300 session: [(counts, valid)], and whether the echo came
        self.problems = []
        self.replies = self.unanswered = self.gripper_sessions = 0
        self.threads = [threading.Thread(target=self._sensor, daemon=True),
                        threading.Thread(target=self._gripper, daemon=True)]

    def start(self):
        benchlib.wait_for(lambda: all(os.path.exists(p) for p in (self.sensor_path, self.gripper_path)),
                          'the devices\' serial lines', 60)
        for thread in self.threads:
            thread.start()

    def stop(self):
        self.stopping.set()
        for thread in self.threads:
            thread.join(self.every + 30)

    def _sensor(self):
        import serial
        while not self.stopping.is_set():
            port = serial.Serial(self.sensor_path, 19200, timeout=5.0)
            try:
                port.write(START_STREAM)
                echoed = port.read(len(STARTED)) == STARTED
                data = bytearray()
                port.timeout = 0.05
                end = time.monotonic() + self.every
                while time.monotonic() < end and not self.stopping.is_set():
                    data += port.read(4096)
                port.write(STOP_STREAM)
                port.timeout = 0.3
                while True:  # what was on its way, until the line is quiet
                    chunk = port.read(4096)
                    if not chunk:
                        break
                    data += chunk
            finally:
                port.close()
            frames = [(struct.unpack('<6h', bytes(data[i + 2:i + 14])),
                       data[i:i + 2] == b'\x20\x4e' and valid_crc(bytes(data[i:i + FRAME])))
                      for i in range(0, len(data) - FRAME + 1, FRAME)]
            self.sessions.append((frames, echoed, len(data) % FRAME))

    def _gripper(self):
        import serial
        while not self.stopping.is_set():
            self.gripper_sessions += 1
            port = serial.Serial(self.gripper_path, 115200, timeout=2.0)
            try:
                end = time.monotonic() + self.every
                while time.monotonic() < end and not self.stopping.is_set():
                    port.reset_input_buffer()
                    port.write(READ_STATUS)
                    reply = port.read(STATUS_REPLY)
                    if len(reply) == STATUS_REPLY and valid_crc(reply) and reply[:3] == bytes([9, 3, 6]):
                        self.replies += 1
                    else:
                        self.unanswered += 1
                    time.sleep(0.1)
            finally:
                port.close()

    def judge(self, published):
        """Rows for the report and problems, against `published`: the topic's messages in counts, in order of
        their stamps."""
        problems, streamed, lost = [], 0, 0
        # Frame k is message start + k plus the driver's zero, which changes only at a SET_ZERO: the steps
        # between consecutive frames are the steps between consecutive messages.
        index = {}
        for i in range(len(published) - 1):
            index.setdefault(_step(published[i], published[i + 1]), []).append(i)
        for n, (frames, echoed, leftover) in enumerate(self.sessions):
            if not echoed:
                problems.append('FT 300 session %d: no echo of the stream\'s start' % n)
            if leftover or not all(valid for _, valid in frames):
                problems.append('FT 300 session %d: a frame with a bad header or CRC, or a partial frame' % n)
            if not frames:
                problems.append('FT 300 session %d: no frame' % n)
                continue
            values = [v for v, _ in frames]
            runs = _zero_stretches(values, published, index)
            if runs is None or not _one_for_one(runs):
                lost += 1
                problems.append('FT 300 session %d: its %d frames are not the topic\'s messages one for one, '
                                'each plus the zero of its moment (%s)' % (
                                    n, len(values), 'no stretch of them found on the topic' if runs is None else
                                    'stretches of one zero: %s' % runs[:20]))
            streamed += len(values)
        if self.unanswered:
            problems.append('2F-140: %d of %d status reads unanswered' % (self.unanswered,
                                                                           self.unanswered + self.replies))
        rows = ['| FT 300 stream sessions (reconnecting every %g s): sessions, frames, sessions not frame for '
                'message with the topic | %d, %d, %d |' % (self.every, len(self.sessions), streamed, lost),
                '| 2F-140 Modbus RTU client (status at 10 Hz, reconnecting every %g s): sessions, replies, '
                'unanswered | %d, %d, %d |' % (self.every, self.gripper_sessions, self.replies, self.unanswered)]
        return rows, problems


def _step(a, b):
    return tuple(y - x for x, y in zip(a, b))


def _one_for_one(runs):
    return all(run >= LEAST_BETWEEN_ZEROS for run in runs[1:-1])


def _zero_stretches(values, published, index):
    """The lengths of the stretches over which frame k minus message start + k is one zero, where the first
    step between frames found among the messages' steps places the frames (of its places, the first that
    makes them one for one); None if no step is found."""
    k = next((k for k in range(len(values) - 1) if _step(values[k], values[k + 1]) in index), None)
    if k is None:
        return None
    runs = None
    for place in index[_step(values[k], values[k + 1])]:
        start = place - k
        if start < 0 or start + len(values) > len(published):
            continue
        runs, zero = [], None
        for j, value in enumerate(values):
            this = _step(published[start + j], value)
            if this == zero:
                runs[-1] += 1
            else:
                runs.append(1)
                zero = this
        if _one_for_one(runs):
            break
    return runs
