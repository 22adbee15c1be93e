"""The 2F-140 on Modbus (devices/network/robotiq_modbus.py): RTU on a real pseudo-terminal and TCP on a real
socket, over the register machine the gripper node runs (kinematic fingers, no master).

The RTU client is minimalmodbus from PyPI, opened on the pseudo-terminal's path with the unit's serial
settings, as Robotiq's robotiq_modbus_rtu node opens its USB adapter: it writes the requests at 0x03E8 with
function 16 and reads the status at 0x07D0 with function 3 or 4. Frames the manual gives byte for byte
(its worked example of section 4) are sent as they are. The TCP client is written from the manual's Modbus
TCP examples, as robotiq_modbus_tcp talks to the gateway (registers from 0, function 16 and 4).
"""
import os
import socket
import struct
import threading

import pytest
import serial

from ur3_ft_gripper_description.devices import gripper_sim
from ur3_ft_gripper_description.devices.network import listen, robotiq_modbus
from test_sim_nodes import SPEC, gripper
from ur3_ft_gripper_testing.modbus_frames import SILENCE, LineClient, crc_framed, garbage, valid_crc

OBJECT_WIDTH = 0.06  # m between the pads
TABLE = robotiq_modbus.read_table()
REQUEST, STATUS = 0x03E8, 0x07D0  # the manual's first registers on the RS-485 line


def status_bytes(registers):
    """The status block's six bytes (manual: gripper status, reserved, fault, position request echo, position,
    current)."""
    return struct.pack('>3H', *registers)


def decoded(registers):
    """{gACT, gGTO, gSTA, gOBJ, gFLT, gPR, gPO, gCU} from the manual's bit layout, written out here."""
    data = status_bytes(registers)
    return dict(gACT=data[0] & 1, gGTO=(data[0] >> 3) & 1, gSTA=(data[0] >> 4) & 3, gOBJ=(data[0] >> 6) & 3,
                gFLT=data[2] & 0x0F, gPR=data[3], gPO=data[4], gCU=data[5])


def request_registers(rACT=0, rGTO=0, rATR=0, rPR=0, rSP=0, rFR=0):
    """The three request registers (manual: action request, reserved, reserved, position, speed, force)."""
    data = bytes([rACT | rGTO << 3 | rATR << 4, 0, 0, rPR, rSP, rFR])
    return list(struct.unpack('>3H', data))


class Line(LineClient):
    """The register machine behind a pseudo-terminal; advance(seconds) runs it as the node's loop does."""

    def __init__(self, tmp_path, **kwargs):
        self.machine, _, _ = gripper(**kwargs)
        self.lock, self.logged = threading.Lock(), []
        self.link = str(tmp_path / 'ttyRobotiq2F')
        self.port = robotiq_modbus.serve_rtu(TABLE, self.machine, self.lock, self.logged.append, link=self.link)
        super().__init__(self.link, TABLE['rtu']['slave_id'], TABLE['rtu']['serial'], self.port)

    def advance(self, seconds, dt=0.02):
        for _ in range(int(round(seconds / dt))):
            with self.lock:
                self.machine.advance(dt)

    def status(self, functioncode=4):
        return decoded(self.client.read_registers(STATUS, 3, functioncode=functioncode))

    def command(self, **registers):
        self.client.write_registers(REQUEST, request_registers(**registers))

@pytest.fixture
def line(tmp_path):
    made = Line(tmp_path, object_width=OBJECT_WIDTH)
    yield made
    made.close()


def test_minimalmodbus_activates_closes_on_an_object_and_opens_as_robotiqs_node_does(line):
    line.command(rACT=0)  # reset
    assert line.status()['gSTA'] == 0
    line.command(rACT=1, rGTO=1, rSP=255, rFR=150)
    line.advance(SPEC.activation_time + 0.1)
    assert (line.status()['gACT'], line.status()['gSTA']) == (1, 3)
    line.command(rACT=1, rGTO=1, rPR=255, rSP=255, rFR=128)
    assert line.status(functioncode=3)['gPR'] == 255  # robotiq_modbus_rtu reads with function 3
    line.advance(3.0)
    held = line.status()
    assert held['gOBJ'] == 2  # stopped on an object while closing
    assert held['gPO'] == pytest.approx(SPEC.scale.position(OBJECT_WIDTH), abs=1)
    # The ROS face publishes the same registers.
    assert {name: line.machine.status()[name] for name in held} == held
    line.command(rACT=1, rGTO=1, rPR=0, rSP=255, rFR=128)
    line.advance(3.0)
    opened = line.status()
    assert (opened['gOBJ'], opened['gPO']) == (3, round(SPEC.scale.position(SPEC.stroke)))
    assert line.logged == []


def test_the_automatic_release_reads_its_faults(line):
    line.command(rACT=1, rGTO=1)
    line.advance(SPEC.activation_time + 0.1)
    line.command(rACT=1, rGTO=1, rPR=255, rSP=255, rFR=128)
    line.advance(3.0)
    line.command(rACT=1, rGTO=1, rATR=1, rPR=255, rSP=255, rFR=128)
    assert line.status()['gFLT'] == gripper_sim.FAULT_AUTO_RELEASE_ACTIVE
    line.advance(10.0)
    assert line.status()['gFLT'] == gripper_sim.FAULT_AUTO_RELEASE_DONE


def test_the_manuals_frames_byte_for_byte(line):
    # Section 4's example: open at full speed and force, rACT and rGTO set; and its answer.
    request = bytes.fromhex('09 10 03 E8 00 03 06 09 00 00 00 FF FF 72 19')
    assert line.raw(request) == bytes.fromhex('09 10 03 E8 00 03 01 30')
    assert {k: line.machine.command[k] for k in ('rACT', 'rGTO', 'rPR', 'rSP', 'rFR')} == dict(
        rACT=1, rGTO=1, rPR=0, rSP=255, rFR=255)
    # The request block reads back as written.
    assert line.client.read_registers(REQUEST, 3, functioncode=3) == [0x0900, 0x0000, 0xFFFF]


def test_function_23_writes_then_reads(line):
    reply = line.raw(crc_framed(bytes([9, 23]) + struct.pack('>HHHHB', STATUS, 3, REQUEST, 3, 6) +
                                struct.pack('>3H', *request_registers(rACT=1, rGTO=1, rSP=255, rFR=255))))
    assert reply[:3] == bytes([9, 23, 6]) and valid_crc(reply)
    assert decoded(struct.unpack('>3H', reply[3:9]))['gPR'] == 0
    assert line.machine.command['rACT'] == 1


@pytest.mark.parametrize('pdu, code, problem', [
    (bytes([5]) + struct.pack('>HH', 0, 0xFF00), 1, 'function code 5 is not one the gripper answers'),
    (bytes([4]) + struct.pack('>HH', 0, 3), 2, 'a read of 3 registers at 0x0000 is outside'),
    (bytes([4]) + struct.pack('>HH', STATUS + 1, 3), 2, 'outside'),
    (bytes([16]) + struct.pack('>HHB3H', STATUS, 3, 6, 1, 2, 3), 2, 'a write of 3 registers at 0x07D0 is outside'),
    (bytes([3]) + struct.pack('>HH', STATUS, 0), 3, 'a read of 0 registers'),
    (bytes([16]) + struct.pack('>HHB2H', REQUEST, 3, 4, 1, 2), 3, 'a write of 3 registers in 4 bytes'),
    (bytes([3]) + struct.pack('>H', STATUS), 3, 'a read of 2 bytes, not 4'),
])
def test_a_request_the_gripper_cannot_serve_gets_its_exception_and_one_line(line, pdu, code, problem):
    before = dict(line.machine.command)
    reply = line.raw(crc_framed(bytes([9]) + pdu))
    assert reply == crc_framed(bytes([9, pdu[0] | 0x80, code]))
    assert len(line.logged) == 1 and problem in line.logged[0], line.logged
    assert line.machine.command == before
    assert line.status()['gSTA'] == 0  # the line goes on


@pytest.mark.parametrize('frame, problem', [
    (bytes.fromhex('09 04 07 D0 00 03 00 00'), 'cannot read'),        # a wrong CRC
    (crc_framed(bytes.fromhex('0A 04 07 D0 00 03')), 'for slave 10'),  # another slave
    (bytes.fromhex('09 04'), 'cannot read'),                           # short
])
def test_a_frame_for_someone_else_or_broken_gets_silence_and_one_line(line, frame, problem):
    assert line.raw(frame, wait=SILENCE) == b''
    assert len(line.logged) == 1 and problem in line.logged[0], line.logged
    assert line.status()['gSTA'] == 0


def test_seeded_garbage_never_stops_the_line(line):
    for frame in garbage(20261128, 40, 9):
        reply = line.raw(frame, wait=2 * SILENCE)  # a reply, or silence
        assert reply == b'' or (reply[0] == 9 and valid_crc(reply)), reply
    assert len(line.logged) <= 40
    line.command(rACT=1, rGTO=1)
    line.advance(SPEC.activation_time + 0.1)
    assert line.status()['gSTA'] == 3


def test_the_link_is_the_users_path_and_goes_with_the_line(tmp_path):
    made = Line(tmp_path)
    assert os.path.realpath(made.link) == made.port.path and made.port.path.startswith('/dev/pts/')
    made.close()
    assert not os.path.lexists(made.link)


def test_a_path_that_is_a_file_is_one_line(tmp_path):
    taken = tmp_path / 'ttyUSB0'
    taken.write_text('')
    with pytest.raises(listen.ListenError) as caught:
        robotiq_modbus.serve_rtu(TABLE, gripper()[0], threading.Lock(), print, link=str(taken))
    assert 'is not a symbolic link' in str(caught.value) and '\n' not in str(caught.value)


def test_the_client_may_come_and_go(line):
    for _ in range(3):
        line.client.serial.close()
        line.client.serial.open()
        assert line.status()['gSTA'] == 0


# -- Modbus TCP, as the gateway serves it --------------------------------------------------------------


class Gateway(object):
    def __init__(self):
        self.machine, _, _ = gripper(object_width=OBJECT_WIDTH)
        self.lock, self.logged = threading.Lock(), []
        self.server = robotiq_modbus.serve_tcp(TABLE, self.machine, self.lock, self.logged.append,
                                               listen.LOOPBACK, port=0)
        self.socket = socket.create_connection((listen.LOOPBACK, self.server.server_address[1]), timeout=10.0)
        self.transaction = 0

    def ask(self, pdu, unit=2):
        """The response PDU to `pdu`, its MBAP header checked (manual: transaction id echoed, protocol 0)."""
        self.transaction += 1
        self.socket.sendall(struct.pack('>HHHB', self.transaction, 0, len(pdu) + 1, unit) + pdu)
        header = self.socket.recv(7)
        transaction, protocol, length, echoed = struct.unpack('>HHHB', header)
        assert (transaction, protocol, echoed) == (self.transaction, 0, unit)
        return self.socket.recv(length - 1)

    def close(self):
        self.socket.close()
        self.server.shutdown()
        self.server.server_close()


@pytest.fixture
def gateway():
    made = Gateway()
    yield made
    made.close()


def test_the_gateway_serves_the_registers_from_zero_as_robotiq_modbus_tcp_reads_them(gateway):
    # The manual's steps: activate (FC16 at 0), read the status (FC04 at 0) until activated.
    assert gateway.ask(bytes([16]) + struct.pack('>HHB3H', 0, 3, 6, *request_registers(rACT=1, rGTO=1))) == \
        bytes([16]) + struct.pack('>HH', 0, 3)
    with gateway.lock:
        for _ in range(int((SPEC.activation_time + 0.1) / 0.02)):
            gateway.machine.advance(0.02)
    reply = gateway.ask(bytes([4]) + struct.pack('>HH', 0, 3))
    assert reply[:2] == bytes([4, 6])
    assert decoded(struct.unpack('>3H', reply[2:]))['gSTA'] == 3
    # Bad input: an exception reply, one line, and the connection goes on.
    assert gateway.ask(bytes([4]) + struct.pack('>HH', 100, 1)) == bytes([0x84, 2])
    assert len(gateway.logged) == 1 and '2F-140 Modbus TCP: 127.0.0.1:' in gateway.logged[0]
    assert decoded(struct.unpack('>3H', gateway.ask(bytes([3]) + struct.pack('>HH', 0, 3))[2:]))['gACT'] == 1


def test_a_taken_tcp_port_is_one_line():
    first = Gateway()
    try:
        with pytest.raises(listen.ListenError) as caught:
            robotiq_modbus.serve_tcp(TABLE, first.machine, first.lock, print, listen.LOOPBACK,
                                     port=first.server.server_address[1])
        assert '2F-140 Modbus TCP cannot listen' in str(caught.value) and '\n' not in str(caught.value)
    finally:
        first.close()


def test_the_table_names_the_gripper_registers():
    names = {name for fields in TABLE['request_bytes'].values() for name in fields}
    assert names <= set(gripper_sim.COMMAND_FIELDS)
    names = {name for fields in TABLE['status_bytes'].values() for name in fields}
    assert names == set(gripper_sim.STATUS_FIELDS)
    assert (TABLE['rtu']['slave_id'], TABLE['rtu']['request_register'], TABLE['rtu']['status_register']) == (
        9, REQUEST, STATUS)
    assert serial.PARITY_NONE == TABLE['rtu']['serial']['parity']
