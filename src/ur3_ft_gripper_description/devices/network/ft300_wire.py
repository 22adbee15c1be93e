"""The FT 300 on its serial line: Modbus RTU on a pseudo-terminal, then the data stream; no ROS.

As the sensor behind its USB adapter: at 19200 8N1 it answers Modbus RTU as slave 9, its registers holding
the force and moment, its identity and the stream's start (config/robotiq_ft300_modbus.yaml). Writing
the start value to the stream register switches it to the data stream: a 16-byte frame per reading, at
the sensor's 100 Hz, until the client sends a run of 0xFF bytes; then it answers Modbus again. This is
how rq_sensor, Robotiq's ROS driver, talks to it. The framing (CRC, slave id) is modbus_tk's.

The readings are the device's own (ft300_sim's SensorModel), handed over one by one as the node
publishes its own (`reading`): the stream carries one frame for each message of the ROS face, in the same
order, and the force registers read the last of them. They are the device's, before the zero that
rq_sensor keeps in the driver, so the unit's offset stays on them.

Bad input, as the sensor meets it: a frame with a wrong CRC or for another slave gets no reply; a
request it cannot serve gets the protocol's exception reply; each costs one log line, and the line goes
on. While it streams, it reads nothing but the 0xFF that stop it.
"""

import struct
import threading

from ..sim_params import PackageFile
from .modbus_line import PseudoTerminal, RegisterDevice, RtuSlave
from ... import yaml_data

TABLE_FILE = PackageFile('config/robotiq_ft300_modbus.yaml')
COUNT_MIN, COUNT_MAX = -32768, 32767


def read_table(path=None):
    with open(path or TABLE_FILE.path()) as stream:
        return yaml_data.load(stream)


def identity_registers(table, identity):
    """{register: value} of the identity blocks for `identity` (serial_number 'ABC-1234', firmware_version
    'FTS-1.2.3', production_year '2026': rq_sensor's own formats); ValueError (one line) for another form."""
    def letters(text, name, form):
        if len(text) < 4 or text[3] != '-' or not all(32 < ord(c) < 127 for c in text[:3]):
            raise ValueError('the FT 300\'s %s %r is not of the form %s, as rq_sensor reads it from the sensor'
                             % (name, text, form))
        return [ord(c) for c in text[:3]]

    firmware, serial_number = identity['firmware_version'], identity['serial_number']
    chars = letters(firmware, 'firmware_version', 'FTS-1.2.3')
    try:
        numbers = [int(n) for n in firmware[4:].split('.')]
        if len(numbers) != 3 or not all(0 <= n <= 255 for n in numbers) or chars[0] != ord('F'):
            raise ValueError
    except ValueError:
        raise ValueError('the FT 300\'s firmware_version %r is not of the form F..-1.2.3 (numbers 0..255; rq_sensor '
                         'takes a sensor whose firmware does not start with F for none)' % firmware) from None
    letters_sn = letters(serial_number, 'serial_number', 'ABC-1234')
    if not serial_number[4:].isdigit() or int(serial_number[4:]) > 0xFFFFFFFF:
        raise ValueError('the FT 300\'s serial_number %r is not of the form ABC-1234' % serial_number)
    number = int(serial_number[4:])
    year = str(identity['production_year'])
    if not year.isdigit() or int(year) > 0xFFFF:
        raise ValueError('the FT 300\'s production_year %r is not a year' % year)
    blocks = table['blocks']
    values = {
        'firmware': [chars[0] << 8 | chars[1], chars[2] << 8 | numbers[0], numbers[1] << 8 | numbers[2]],
        'serial_number': [letters_sn[0] << 8 | letters_sn[1], letters_sn[2] << 8, number & 0xFFFF, number >> 16],
        'production_year': [int(year)],
    }
    return {blocks[name]['first'] + i: value for name, registers in values.items()
            for i, value in enumerate(registers)}


class Ft300Registers(RegisterDevice):
    """The sensor's registers: the last reading's counts (`counts`, under `lock`), its accelerometer's
    (`acceleration_counts`), its identity, and the stream's start, which sets `start_pending` for the line
    to act on once the reply is out."""

    who = 'the sensor'

    def __init__(self, table, identity, lock):
        super().__init__(table)
        self.blocks = table['blocks']
        self.fixed = identity_registers(table, identity)
        self.stream_register, self.stream_start = table['stream_register'], table['stream_start']
        self.lock = lock
        self.counts = [0] * 6
        self.acceleration_counts = [0] * 3
        self.start_pending = False

    def read(self, address, count):
        for name, measured in (('wrench', 'counts'), ('acceleration', 'acceleration_counts')):
            block = self.blocks[name]
            if block['first'] <= address and address + count <= block['first'] + block['count']:
                with self.lock:
                    counts = list(getattr(self, measured))
                return [c & 0xFFFF for c in counts[address - block['first']:address - block['first'] + count]]
        for block in self.blocks.values():
            if block['first'] <= address and address + count <= block['first'] + block['count']:
                return [self.fixed[address + i] for i in range(count)]
        return None

    def write(self, address, values):
        if (address, len(values)) != (self.stream_register, 1):
            return 'illegal_data_address', ('a write of %d registers at %d: the sensor takes writes only to register '
                                            '%d, the stream\'s start' % (len(values), address, self.stream_register))
        if values[0] != self.stream_start:
            return 'illegal_data_value', ('register %d takes 0x%04X (start the stream), not 0x%04X'
                                          % (self.stream_register, self.stream_start, values[0]))
        self.start_pending = True
        return None

    def outside(self, what, address, count, writing):
        blocks = ', '.join('%d..%d' % (b['first'], b['first'] + b['count'] - 1) for b in self.blocks.values())
        return "%s %d registers at %d is outside the sensor's registers (%s)" % (what, count, address, blocks)


class Ft300Line(object):
    """The sensor's side of the line: answer(bytes) -> reply bytes for what the client sent, reading(values)
    for each reading the node publishes. `send(bytes)` writes to the client (the line's)."""

    def __init__(self, table, identity, log):
        self.lock = threading.Lock()
        self.registers = Ft300Registers(table, identity, self.lock)
        self.modbus = RtuSlave(self.registers, table['slave_id'], 'FT 300 Modbus RTU', log)  # the library first
        self.crc = _crc_function()
        stream = table['stream']
        self.header = bytes(stream['header'])
        self.resolution = [stream['force_resolution']] * 3 + [stream['torque_resolution']] * 3
        self.acceleration_resolution = table['acceleration_resolution']
        self.stop_byte, self.stop_count = stream['stop_byte'], stream['stop_count']
        self.streaming = False
        self._stop_run = 0
        self.send = None

    # -- the readings -------------------------------------------------------------------

    def reading(self, values, acceleration=None):
        """One reading (fx, fy, fz in N, mx, my, mz in N m, in the stream's resolution), as the node publishes
        it: the force registers hold it, and a streaming sensor sends its frame. `acceleration` (ax, ay, az in
        g), the accelerometer's at the same time, goes to its registers."""
        counts = _counts(values, self.resolution)
        with self.lock:
            self.registers.counts = counts
            if acceleration is not None:
                self.registers.acceleration_counts = _counts(acceleration, [self.acceleration_resolution] * 3)
            if not self.streaming or self.send is None:
                return
        self.send(self.frame(counts))

    def frame(self, counts):
        data = self.header + struct.pack('<6h', *counts)
        return data + self.crc(data)

    # -- what the client sends ----------------------------------------------------------

    def answer(self, data):
        with self.lock:
            if self.streaming:
                self._read_while_streaming(data)
                return b''
        if data.count(self.stop_byte) == len(data):
            return b''  # a stop sent to a sensor that is not streaming: nothing to stop
        response = self.modbus.answer(data)
        if not self.registers.start_pending:
            return response
        with self.lock:  # the reply first, then the stream's frames (rq_sensor reads the reply, then frames)
            self.send(response)
            self.streaming, self._stop_run, self.registers.start_pending = True, 0, False
        return b''

    def _read_while_streaming(self, data):
        for byte in data:
            self._stop_run = self._stop_run + 1 if byte == self.stop_byte else 0
            if self._stop_run >= self.stop_count:
                self.streaming, self._stop_run = False, 0
                return  # what follows the stop in this burst is more of it


def _counts(values, resolutions):
    """Each value in counts of its resolution, as a signed 16-bit register holds it (clamped)."""
    return [min(max(int(round(v / r)), COUNT_MIN), COUNT_MAX) for v, r in zip(values, resolutions)]


def _crc_function():
    """bytes -> the two CRC bytes of a Modbus RTU frame (least significant first), from modbus_tk."""
    from modbus_tk import utils
    return lambda data: struct.pack('>H', utils.calculate_crc(data))


def serve(table, identity, log, link=None):
    """The FT 300's line on a pseudo-terminal, serving in a thread of its own: (Ft300Line, PseudoTerminal)."""
    sensor = Ft300Line(table, identity, log)
    line = PseudoTerminal(sensor, table['frame_gap'], link, "the FT 300's")
    sensor.send = line.send
    return sensor, line.start('FT 300 Modbus RTU')
