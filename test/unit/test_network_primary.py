"""The primary and secondary interfaces (30001, 30002) on real sockets over the arm's core.

The client reads packages as UR's client interface document lays them out
(int32 size, uint8 type; a robot state's sub-packages each with their own
size and type), written here, not taken from the package's table. Known
truths: the sub-package sizes of the first robot state a UR5e URSim 5.8
sends (ur_client_library's test capture), the joint positions the robot
holds, and ur_robot_driver's calibration check, which hashes the DH
parameters of the kinematics sub-package as ur_client_library does and
compares the hash with ur_description's default_kinematics.yaml.
"""
import math
import os
import select
import socket
import struct
import time

import pytest
import rospkg
import yaml

from controller_cell import Cell
from ur3_ft_gripper_description import urscript
from test_ur_arm_core import START

ROBOT_STATE, ROBOT_MESSAGE = 16, 20
ROBOT_MODE_DATA, JOINT_DATA, MASTERBOARD_DATA, KINEMATICS_INFO = 0, 1, 3, 5
# (sub-package type, its size) in the order URSim 5.8's UR5e sends its robot state.
E_SERIES_STATE = [(0, 47), (1, 251), (4, 101), (5, 225), (9, 53), (3, 75), (2, 37), (6, 445), (7, 61), (8, 9),
                  (10, 43), (11, 26), (12, 8)]
POWER_OFF, RUNNING = 3, 7


class PrimaryClient(object):
    def __init__(self, port):
        self.socket = socket.create_connection(('127.0.0.1', port), timeout=10.0)

    def read(self, count):
        """Exactly `count` bytes, read straight from the socket (no buffer, so select() sees what waits)."""
        data = b''
        while len(data) < count:
            chunk = self.socket.recv(count - len(data))
            if not chunk:
                raise EOFError('the controller closed the connection')
            data += chunk
        return data

    def package(self):
        """(type, body after the 5-byte header)."""
        size, kind = struct.unpack('>iB', self.read(5))
        return kind, self.read(size - 5)

    def state(self):
        """{sub-package type: its body} and their order, of the next robot state."""
        kind, body = self.package()
        assert kind == ROBOT_STATE, kind
        subs, order = {}, []
        while body:
            size, sub = struct.unpack_from('>iB', body)
            subs[sub] = body[5:size]
            order.append((sub, size))
            body = body[size:]
        return subs, order

    def newest_state(self, cell):
        """Step the cell 0.1 s and read past older states to the last one sent (stamped within the last
        0.1 s of the controller's time)."""
        cell.step(int(math.ceil(0.1 / cell.dt - 1e-9)))
        return self.states_until(cell)[-1]

    def states_until(self, cell):
        """The states up to the last one the cell has sent, stamped within its last 0.1 s."""
        newest, states = cell.core.uptime * 1000.0 - 100.0, []
        while not states or timestamp(states[-1][0]) <= newest + 1e-6:
            states.append(self.state())
        return states

    def send(self, text):
        self.socket.sendall(text.encode())

    def close(self):
        self.socket.close()


def timestamp(subs):
    """ROBOT_MODE_DATA's timestamp (ms of the controller's time)."""
    return struct.unpack_from('>Q', subs[ROBOT_MODE_DATA])[0]


def joint_positions(subs):
    return [struct.unpack_from('>d', subs[JOINT_DATA], 41 * joint)[0] for joint in range(6)]


def robot_mode(subs):
    """(is_robot_power_on, robot_mode) of ROBOT_MODE_DATA: a uint64 timestamp, seven bools, the mode."""
    power_on = struct.unpack_from('>?', subs[ROBOT_MODE_DATA], 10)[0]
    return power_on, struct.unpack_from('>B', subs[ROBOT_MODE_DATA], 15)[0]


def libstdcxx_hash(data, seed=0xc70f6907):
    """std::hash<std::string> of libstdc++ on 64-bit (its _Hash_bytes), as ur_client_library's toHash uses it."""
    mask, mul = (1 << 64) - 1, (0xc6a4a793 << 32) + 0x5bd1e995

    def shift_mix(v):
        return v ^ (v >> 47)

    length = len(data)
    value = (seed ^ (length * mul)) & mask
    aligned = length & ~7
    for i in range(0, aligned, 8):
        chunk = shift_mix(int.from_bytes(data[i:i + 8], 'little') * mul & mask) * mul & mask
        value = (value ^ chunk) * mul & mask
    if length & 7:
        value = (value ^ int.from_bytes(data[aligned:], 'little')) * mul & mask
    value = shift_mix(value) * mul & mask
    return shift_mix(value)


def calibration_hash(theta, a, d, alpha):
    """ur_client_library's KinematicsInfo::toHash: per joint theta, d, a, alpha at C++'s default precision."""
    text = ''.join('%g%g%g%g' % values for values in zip(theta, d, a, alpha))
    return 'calib_%d' % libstdcxx_hash(text.encode())


def description_hash(ur_type):
    path = os.path.join(rospkg.RosPack().get_path('ur_description'), 'config', ur_type, 'default_kinematics.yaml')
    with open(path) as stream:
        return yaml.safe_load(stream)['kinematics']['hash']


@pytest.fixture(params=['ur5e', 'ur3'])
def cell(request, configured_model):
    cell = Cell(configured_model, request.param)
    yield cell
    cell.faces.shutdown()


def test_the_hash_is_ur_client_librarys():
    """The check of the check: the UR3's nominal DH table, as ur_description's file hashes it."""
    assert calibration_hash([0.0] * 6, [0, -0.24365, -0.21325, 0, 0, 0], [0.1519, 0, 0, 0.11235, 0.08535, 0.0819],
                            [1.570796327, 0, 0, 1.570796327, -1.570796327, 0]) == description_hash('ur3')


@pytest.mark.parametrize('port', ['primary', 'secondary'])
def test_a_client_gets_the_version_then_a_robot_state_each_tenth_of_a_second(cell, port):
    client = PrimaryClient(cell.faces.port(port))
    kind, body = client.package()
    assert kind == ROBOT_MESSAGE
    _, source, message_type, name_size = struct.unpack_from('>QbBb', body)
    assert message_type == 3 and body[11:11 + name_size] == b'URControl'
    assert struct.unpack_from('>BBii', body, 11 + name_size) == cell.core.software.version
    subs, order = client.newest_state(cell)
    if cell.core.software.e_series:
        assert order == E_SERIES_STATE
    else:  # the CB3 has no safety, tool communication or tool mode sub-packages
        assert [sub for sub, _ in order] == [sub for sub, _ in E_SERIES_STATE if sub not in (10, 11, 12)]
    assert joint_positions(subs) == pytest.approx(START, abs=1e-12)
    assert robot_mode(subs) == (True, RUNNING)
    before = timestamp(subs)
    cell.step(int(round(1.0 / cell.dt)))
    stamps = [timestamp(state) for state, _ in client.states_until(cell)]
    assert len(stamps) == 10 and stamps[-1] <= before + 1000  # 1 s of the controller's time at 10 Hz
    client.close()


def test_the_kinematics_pass_ur_robot_drivers_calibration_check(cell):
    client = PrimaryClient(cell.faces.port('primary'))
    client.package()
    subs, _ = client.newest_state(cell)
    values = struct.unpack_from('>6I24dI', subs[KINEMATICS_INFO])
    theta, a, d, alpha = (values[6 + 6 * i:12 + 6 * i] for i in range(4))
    assert calibration_hash(theta, a, d, alpha) == description_hash(cell.core.software.ur_type)
    client.close()


def test_the_primary_interface_takes_its_commands_and_the_secondary_a_program(cell):
    primary, secondary = PrimaryClient(cell.faces.port('primary')), PrimaryClient(cell.faces.port('secondary'))
    primary.package()
    secondary.package()
    # A program first: the robot runs programs only while RUNNING.
    secondary.send('sec outputs():\n  set_standard_digital_out(4, True)\nend\n')
    cell.step_until(lambda: cell.core.robot.digital_out[4], 'the secondary\'s program setting output 4')
    primary.send('power off\n')
    cell.step_until(lambda: cell.core.robot.robot_mode == 'POWER_OFF', 'power off from the primary interface')
    subs, _ = secondary.newest_state(cell)
    assert robot_mode(subs) == (False, POWER_OFF)
    assert struct.unpack_from('>i', subs[MASTERBOARD_DATA], 4)[0] == 1 << 4
    primary.close()
    secondary.close()


def test_the_read_only_twins_send_the_same_and_take_nothing_in(cell):
    primary, read_only = PrimaryClient(cell.faces.port('primary')), PrimaryClient(cell.faces.port('primary_read_only'))
    secondary_read_only = PrimaryClient(cell.faces.port('secondary_read_only'))
    for client in (primary, read_only, secondary_read_only):
        assert client.package()[0] == ROBOT_MESSAGE  # the version message
    read_only.send('power off\n')
    secondary_read_only.send('sec lit():\n  set_standard_digital_out(5, True)\nend\n')
    cell.step_until(lambda: len(cell.logged) == 2, 'a line from each read-only face')
    subs, _ = read_only.newest_state(cell)
    assert robot_mode(subs) == (True, RUNNING) and not cell.core.robot.digital_out[5]
    assert sorted(line.split(':')[0] for line in cell.logged) == ['primary interface (read-only)',
                                                                  'secondary interface (read-only)']
    assert all('read-only' in line for line in cell.logged)
    assert [s for s, _ in secondary_read_only.newest_state(cell)[1]] == [s for s, _ in primary.newest_state(cell)[1]]
    for client in (primary, read_only, secondary_read_only):
        client.close()


def test_a_program_is_parsed_before_the_face_takes_the_cores_lock(cell):
    # The control cycle holds that lock: a parse inside it (tenths of a second for a driver's program) would
    # stall every stream the robot sends, which a real controller's never do.
    primary = PrimaryClient(cell.faces.port('primary'))
    primary.package()
    primary.send('def lit():\n  set_standard_digital_out(3, True)\nend\n')
    cell.step_until(lambda: cell.core.robot.digital_out[3], 'the program setting output 3')
    with cell.lock:
        calls = list(cell.calls)
    started = [args for name, args in calls if name == 'start_program']
    assert len(started) == 1 and isinstance(started[0][0], urscript.Program)
    assert not [name for name, args in calls if any('set_standard_digital_out' in str(a) for a in args)]
    primary.close()


def robot_messages(client, cell, condition, what, seconds=30.0):
    """Step the cell until the robot messages read satisfy condition(messages); the messages, each (type,
    body after the message header). The faces' threads take text in while it steps (the wall clock)."""
    deadline, messages = time.monotonic() + seconds, []
    while not condition(messages):
        assert time.monotonic() < deadline, '%s: not within %g s; read %r' % (what, seconds, messages)
        cell.step()
        while select.select([client.socket], [], [], 0)[0]:
            kind, body = client.package()
            if kind == ROBOT_MESSAGE:
                messages.append((body[9], body[10:]))
    return messages


def key(message):
    """(title, text) of a KEY message's body: code, argument, the title's size, the title, the text."""
    size = message[8]
    return message[9:9 + size].decode(), message[9 + size:].decode()


def test_the_primary_interface_announces_a_programs_start_and_end_and_its_runtime_exception(cell):
    client = PrimaryClient(cell.faces.port('primary'))
    client.package()
    client.send('def announced():\n  sleep(0.1)\nend\n')
    keys = lambda messages: [key(body) for kind, body in messages if kind == 7]  # noqa: E731
    robot_messages(client, cell, lambda m: ('PROGRAM_XXX_STOPPED', 'announced') in keys(m), 'the program\'s end')
    client.send('def failing():\n  x = [1, 2]\n  y = x[5]\nend\n')
    messages = robot_messages(client, cell, lambda m: any(kind == 10 for kind, _ in m), 'the runtime exception')
    assert ('PROGRAM_XXX_STARTED', 'failing') in keys(messages)
    line, column = struct.unpack_from('>II', [body for kind, body in messages if kind == 10][0])
    assert line == 3
    client.close()


def test_a_programs_textmsg_reaches_the_primary_clients_between_its_start_and_end(cell):
    # As ur_client_library's test against the robot reads it: KEY started, TEXT "still running", KEY stopped.
    client = PrimaryClient(cell.faces.port('primary'))
    client.package()
    client.send('def talking():\n  textmsg("still ", "running")\n  sleep(0.1)\n  sync()\nend\n')
    messages = robot_messages(client, cell, lambda m: any(kind == 7 and key(body)[0] == 'PROGRAM_XXX_STOPPED'
                                                          for kind, body in m), 'the program\'s end')
    said = [(kind, key(body) if kind == 7 else body.decode()) for kind, body in messages if kind in (0, 7)]
    assert said == [(7, ('PROGRAM_XXX_STARTED', 'talking')), (0, 'still running'),
                    (7, ('PROGRAM_XXX_STOPPED', 'talking'))]
    client.close()


def test_a_loop_of_textmsg_sends_a_few_a_cycle_and_the_client_keeps_its_connection(cell):
    client = PrimaryClient(cell.faces.port('primary'))
    client.package()
    client.send('def chatty():\n  i = 0\n  while i < 150:\n    textmsg("line ", i)\n    i = i + 1\n  end\n'
                '  sleep(0.1)\nend\n')
    messages = robot_messages(client, cell, lambda m: any(kind == 7 and key(body)[0] == 'PROGRAM_XXX_STOPPED'
                                                          for kind, body in m), 'the program\'s end')
    texts = [body.decode() for kind, body in messages if kind == 0]
    # The loop runs within a cycle or two of the controller's budget: ten lines from each, in order.
    assert texts[:10] == ['line %d' % i for i in range(10)] and len(texts) <= 20, texts
    assert all('line %d' % i in cell.core.robot.log for i in range(150)), 'the log keeps every line'
    client.close()
