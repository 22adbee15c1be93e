"""The FT 300 on its serial line (devices/network/ft300_wire.py): Modbus RTU and the data stream on a real
pseudo-terminal, fed with readings as ft300_sim hands them over (no master).

Clients: minimalmodbus (PyPI) for the registers, with the sensor's serial settings; and rq_sensor's own
requests, byte for byte as Robotiq's driver sends them (its probe, identity reads and the stream's start),
with the stream read as the manual lays its frames out and the CRC computed as the Modbus specification
gives it, independently of the library the sensor's side frames with.
"""
import random
import struct
import threading
import time

import pytest

from ur3_ft_gripper_description.devices.network import ft300_wire, listen
from ur3_ft_gripper_testing.modbus_frames import SILENCE, LineClient, crc_framed, garbage, valid_crc

TABLE = ft300_wire.read_table()
IDENTITY = dict(serial_number='SIM-0001', firmware_version='FTS-0.0.0', production_year='2026')
# rq_sensor's requests (rq_sensor_com.cpp), and the sensor's answer to the stream's start.
PROBE = bytes.fromhex('09 03 01 F4 00 01 C5 4C')
START_STREAM = bytes.fromhex('09 10 01 9A 00 01 02 02 00 CD CA')
STARTED = bytes.fromhex('09 10 01 9A 00 01 21 52')
STOP_BURST = b'\xff' * 50


def signed(registers):
    return [r - 0x10000 if r & 0x8000 else r for r in registers]


def stream_frames(data):
    """The manual's frames in `data`: 0x20 0x4E, six int16 least significant byte first, CRC; [(counts), ...]."""
    frames = []
    for start in range(0, len(data) - len(data) % 16, 16):
        frame = data[start:start + 16]
        assert frame[:2] == b'\x20\x4e', frame.hex(' ')
        assert valid_crc(frame), frame.hex(' ')
        frames.append(struct.unpack('<6h', frame[2:14]))
    assert len(data) % 16 == 0, 'a partial frame: %d bytes' % len(data)
    return frames


class Line(LineClient):
    def __init__(self, tmp_path):
        self.logged = []
        self.link = str(tmp_path / 'ttyFT300')
        self.sensor, self.port = ft300_wire.serve(TABLE, IDENTITY, self.logged.append, link=self.link)
        super().__init__(self.link, TABLE['slave_id'], TABLE['serial'], self.port)

    def read_exactly(self, size):
        port = self.client.serial
        port.timeout = 10.0
        data = port.read(size)
        port.timeout = 2.0
        return data

    def drain(self, quiet=0.5):
        """What comes until `quiet` s pass without a byte."""
        port, data = self.client.serial, b''
        port.timeout = quiet
        while True:
            chunk = port.read(4096)
            if not chunk:
                port.timeout = 2.0
                return data
            data += chunk

@pytest.fixture
def line(tmp_path):
    made = Line(tmp_path)
    yield made
    made.close()


def test_rq_sensors_probe_and_identity_reads_give_back_the_identity_in_its_formats(line):
    reply = line.raw(PROBE)
    assert reply[:3] == bytes([9, 3, 2]) and valid_crc(reply)
    assert chr(reply[3]) == 'F'  # rq_sensor takes any other first letter for no sensor
    firmware = line.client.read_registers(500, 3)
    data = struct.pack('>3H', *firmware)
    assert '%c%c%c-%d.%d.%d' % tuple(data) == IDENTITY['firmware_version']
    serial_number = line.client.read_registers(510, 4)
    letters = struct.pack('>2H', *serial_number[:2])
    assert '%c%c%c-%04d' % (letters[0], letters[1], letters[2], serial_number[3] << 16 | serial_number[2]) == \
        IDENTITY['serial_number']
    assert line.client.read_register(514) == int(IDENTITY['production_year'])
    assert line.logged == []


def test_the_force_registers_hold_the_last_reading_in_counts(line):
    line.sensor.reading((1.23, -4.56, 78.9, 0.123, -0.456, 7.891))
    assert signed(line.client.read_registers(180, 6, functioncode=3)) == [123, -456, 7890, 123, -456, 7891]
    assert signed(line.client.read_registers(183, 3, functioncode=4)) == [123, -456, 7891]


def test_the_accelerometer_registers_hold_the_readings_acceleration_in_thousandths_of_g(line):
    # Robotiq's FT-150/300 manual: registers 190 to 192, acceleration X, Y, Z (g) = value / 1000.
    assert signed(line.client.read_registers(190, 3)) == [0, 0, 0]
    line.sensor.reading((1.0, 2.0, 3.0, 0.1, 0.2, 0.3), (0.0123, -0.5, 0.866))
    assert signed(line.client.read_registers(190, 3, functioncode=3)) == [12, -500, 866]
    assert signed(line.client.read_registers(192, 1, functioncode=4)) == [866]
    line.sensor.reading((1.0, 2.0, 3.0, 0.1, 0.2, 0.3))  # a reading without one keeps the last
    assert signed(line.client.read_registers(190, 3)) == [12, -500, 866]
    assert line.logged == []


def test_the_stream_carries_one_frame_per_reading_in_order_until_the_stop(line):
    assert line.raw(START_STREAM)[:8] == STARTED
    rng = random.Random(300)
    readings = [tuple(round(rng.uniform(-300, 300), 2) for _ in range(3)) +
                tuple(round(rng.uniform(-30, 30), 3) for _ in range(3)) for _ in range(1000)]  # 10 s at 100 Hz

    def feed():
        for values in readings:
            line.sensor.reading(values)
            time.sleep(0.0005)  # the node hands them over one by one; the reader keeps up
    feeder = threading.Thread(target=feed)
    feeder.start()
    data = line.read_exactly(16 * len(readings))
    feeder.join()
    frames = stream_frames(data)
    assert len(frames) == len(readings)
    expected = [tuple(int(round(v * 100)) for v in r[:3]) + tuple(int(round(v * 1000)) for v in r[3:])
                for r in readings]
    assert frames == expected
    # While it streams the sensor reads nothing but the stop; the stop as rq_sensor sends it, in bursts.
    line.client.serial.write(STOP_BURST)
    assert line.drain() == b''  # every frame was read: nothing was on its way
    line.sensor.reading((1.0,) * 6)
    assert line.client.read_register(180, signed=True) == 100  # Modbus again, and no frame before it
    assert line.logged == []


def test_a_stream_to_nobody_costs_nothing_and_stops_as_usual(line):
    assert line.raw(START_STREAM)[:8] == STARTED
    for _ in range(20000):  # more than the line keeps for a client: the frames nobody reads are dropped
        line.sensor.reading((0.5,) * 6)
    line.client.serial.write(STOP_BURST)
    # As rq_sensor stops it: the stop, then what was on its way until the line is quiet.
    data = line.drain()
    assert 0 < len(data) <= 16 * 20000 // 2 and len(data) % 16 == 0, len(data)
    assert set(stream_frames(data)) == {(50, 50, 50, 500, 500, 500)}
    assert line.client.read_register(180, signed=True) == 50


@pytest.mark.parametrize('pdu, code, problem', [
    (bytes([5]) + struct.pack('>HH', 0, 0xFF00), 1, 'function code 5 is not one the sensor answers'),
    (bytes([3]) + struct.pack('>HH', 0, 1), 2, 'a read of 1 registers at 0 is outside'),
    (bytes([3]) + struct.pack('>HH', 184, 3), 2, 'outside'),
    (bytes([16]) + struct.pack('>HHBH', 180, 1, 2, 5), 2, 'only to register 410'),
    (bytes([16]) + struct.pack('>HHBH', 410, 1, 2, 0x0100), 3, 'takes 0x0200'),
    (bytes([3]) + struct.pack('>HH', 180, 200), 3, 'a read of 200 registers'),
])
def test_a_request_the_sensor_cannot_serve_gets_its_exception_and_one_line(line, pdu, code, problem):
    assert line.raw(crc_framed(bytes([9]) + pdu)) == crc_framed(bytes([9, pdu[0] | 0x80, code]))
    assert len(line.logged) == 1 and problem in line.logged[0], line.logged
    assert not line.sensor.streaming
    assert line.client.read_register(514) == 2026  # the line goes on


@pytest.mark.parametrize('frame, problem', [
    (PROBE[:-1] + b'\x00', 'cannot read'),                     # a wrong CRC
    (crc_framed(bytes.fromhex('0A 03 01 F4 00 01')), 'for slave 10'),
    (b'\x09', 'cannot read'),
])
def test_a_frame_for_someone_else_or_broken_gets_silence_and_one_line(line, frame, problem):
    assert line.raw(frame, wait=SILENCE) == b''
    assert len(line.logged) == 1 and problem in line.logged[0], line.logged
    assert line.client.read_register(514) == 2026


def test_a_stop_without_a_stream_is_nothing(line):
    assert line.raw(STOP_BURST, wait=SILENCE) == b''
    assert line.logged == []


def test_seeded_garbage_never_stops_the_line(line):
    for frame in garbage(20261128, 40, 9):
        reply = line.raw(frame, wait=2 * SILENCE)  # a reply, or silence
        assert reply == b'' or (reply[0] == 9 and valid_crc(reply)), reply
    if line.sensor.streaming:  # a garbage write that happened to start it
        line.client.serial.write(STOP_BURST)
        time.sleep(0.1)
    assert line.client.read_register(514) == 2026


@pytest.mark.parametrize('field, value, problem', [
    ('firmware_version', 'SIM-0.0.0', 'does not start with F'),
    ('firmware_version', 'FTS-1.2', 'form F..-1.2.3'),
    ('serial_number', 'SIM0001', 'not of the form ABC-1234'),
    ('serial_number', 'SIM-00x1', 'not of the form ABC-1234'),
    ('production_year', 'next year', 'not a year'),
])
def test_an_identity_the_registers_cannot_hold_is_one_line(field, value, problem):
    with pytest.raises(ValueError) as caught:
        ft300_wire.identity_registers(TABLE, dict(IDENTITY, **{field: value}))
    assert problem in str(caught.value) and '\n' not in str(caught.value)


def test_a_path_that_is_a_file_is_one_line(tmp_path):
    taken = tmp_path / 'ttyUSB0'
    taken.write_text('')
    with pytest.raises(listen.ListenError) as caught:
        ft300_wire.serve(TABLE, IDENTITY, print, link=str(taken))
    assert "the FT 300's serial port" in str(caught.value) and '\n' not in str(caught.value)
