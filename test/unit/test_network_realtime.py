"""The real-time interface (30003) on a real socket over the arm's core, and URScript sent as text.

The client reads the package by the byte offsets of UR's client interface
document (written here, not taken from the package's layout file): the size
first, then doubles; time at byte 4, q actual at 252, the TCP pose at 444,
the robot mode at 756, the digital outputs at 1044, the program state at
1052. What it reads is checked against what the robot did.
"""
import select
import socket
import struct
import time

import pytest

from ur3_ft_gripper_description.devices.network.realtime import Layout
from ur3_ft_gripper_description.devices.network.script_text import ScriptError, ScriptReader
from ur3_ft_gripper_description.number_text import number_list
from controller_cell import TAKE_IN, Cell

TARGET = [0.3, -1.4, 1.3, -1.5, -1.5, 0.4]
# UR's document: the package's length by software version.
PACKAGE_BYTES = {('cb3', (3, 5, 0)): 1108, ('cb3', (3, 14, 3)): 1220, ('e_series', (5, 0, 0)): 1108,
                 ('e_series', (5, 9, 4)): 1220}
OFFSET = {'time': 4, 'q_actual': 252, 'tool_vector_actual': 444, 'robot_mode': 756, 'digital_outputs': 1044,
          'program_state': 1052}
RUNNING, PROGRAM_PLAYING, PROGRAM_STOPPED = 7, 2, 1


class RealtimeClient(object):
    def __init__(self, port):
        self.socket = socket.create_connection(('127.0.0.1', port), timeout=10.0)
        self.stream = self.socket.makefile('rb')

    def package(self):
        size, = struct.unpack('>i', self.stream.read(4))
        data = struct.pack('>i', size) + self.stream.read(size - 4)
        assert len(data) == size
        return data

    def taken_in(self, cell):
        """Step the cell until the face sends this client its first package (the server's thread takes the
        connection in: the wall clock bounds that wait); that package."""
        deadline = time.monotonic() + TAKE_IN
        while not select.select([self.socket], [], [], 0.001)[0]:
            assert time.monotonic() < deadline, 'no package within %g s' % TAKE_IN
            cell.step()
        return self.package()

    def send(self, text):
        self.socket.sendall(text.encode())

    def close(self):
        self.stream.close()
        self.socket.close()


def run_for(cell, condition, what, seconds):
    """Step the cell until condition() holds after a cycle, within `seconds` of the controller's time."""
    cycles = 0
    while not condition():
        assert cycles * cell.dt < seconds, '%s did not happen within %g s' % (what, seconds)
        cell.step()
        cycles += 1


def doubles(data, name, count=1):
    values = struct.unpack_from('>%dd' % count, data, OFFSET[name])
    return values[0] if count == 1 else list(values)


@pytest.fixture(params=['ur5e', 'ur3'])
def cell(request, configured_model):
    cell = Cell(configured_model, request.param)
    cell.port = cell.faces.port('realtime')
    yield cell
    cell.faces.shutdown()


@pytest.mark.parametrize('generation, version', sorted(PACKAGE_BYTES))
def test_the_package_has_the_documents_length_for_each_version(generation, version):
    assert Layout(generation, version).size == PACKAGE_BYTES[(generation, version)]


def test_a_package_comes_every_control_cycle_with_the_controllers_time(cell):
    client = RealtimeClient(cell.port)
    first = doubles(client.taken_in(cell), 'time')
    cell.step(10)
    times = [doubles(client.package(), 'time') for _ in range(10)]
    assert times == pytest.approx([first + (i + 1) * cell.dt for i in range(10)], abs=1e-9)
    client.close()


def test_a_program_sent_as_text_moves_the_arm_the_package_reads(cell):
    client = RealtimeClient(cell.port)
    client.taken_in(cell)
    client.send('def p():\n  movej([%s], a=3, v=2)\n' % number_list(TARGET))
    client.send('end\n')  # a program may come in pieces
    cell.step_until(lambda: cell.core.script_running, 'the program to start')
    run_for(cell, lambda: not cell.core.script_running, 'the program to end', 10.0)
    data = None
    while True:  # the newest package
        data = client.package()
        if doubles(data, 'time') == pytest.approx(cell.core.uptime, abs=1e-9):
            break
    assert doubles(data, 'q_actual', 6) == pytest.approx(TARGET, abs=1e-6)
    with cell.lock:
        pose = cell.core.script_robot.call('get_actual_tcp_pose', [], {})
    assert doubles(data, 'tool_vector_actual', 6) == pytest.approx(list(pose), abs=1e-9)
    assert doubles(data, 'robot_mode') == RUNNING and doubles(data, 'program_state') == PROGRAM_STOPPED
    client.close()


def test_a_line_is_a_program_of_its_own(cell):
    client = RealtimeClient(cell.port)
    client.taken_in(cell)
    client.send('set_standard_digital_out(2, True)\n')
    cell.step_until(lambda: cell.core.robot.digital_out[2], 'digital output 2 on')
    while True:
        data = client.package()
        if doubles(data, 'time') == pytest.approx(cell.core.uptime, abs=1e-9):
            break
    assert doubles(data, 'digital_outputs') == 1 << 2
    client.close()


def test_text_that_is_not_urscript_costs_the_connection_and_the_robot_goes_on(cell):
    bad = socket.create_connection(('127.0.0.1', cell.port), timeout=10.0)
    bad.sendall(b'movej(\xff)\n')
    cell.step()
    bad.settimeout(10.0)
    while bad.recv(65536):
        pass  # packages sent before the close; then the end of the stream
    bad.close()
    assert len(cell.logged) == 1 and 'not UTF-8' in cell.logged[0] and 'connection is closed' in cell.logged[0]
    good = RealtimeClient(cell.port)
    assert doubles(good.taken_in(cell), 'time') > 0
    good.close()


def test_the_read_only_twin_sends_the_same_package_and_runs_nothing(cell):
    read_only = RealtimeClient(cell.faces.port('realtime_read_only'))
    package = read_only.taken_in(cell)
    assert len(package) == struct.unpack('>i', package[:4])[0] == len(RealtimeClient(cell.port).taken_in(cell))
    read_only.send('set_standard_digital_out(6, True)\n')
    cell.step_until(lambda: cell.logged, 'the face\'s line on the text it was sent')
    cell.step(10)
    assert not cell.core.robot.digital_out[6]
    assert len(cell.logged) == 1 and 'read-only' in cell.logged[0] and 'port 30003' in cell.logged[0]
    while doubles(read_only.package(), 'time') != pytest.approx(cell.core.uptime, abs=1e-9):
        pass  # the twin goes on sending, to the last cycle
    read_only.close()


def test_the_reader_frames_programs_as_the_controller_does():
    reader = ScriptReader()
    assert reader.feed(b'textmsg("a")\n\ndef p():\n  if True:\n    sleep(1)\n') == ['textmsg("a")\n']
    assert reader.feed(b'  end\nend') == []  # the last end not yet a line
    assert reader.feed(b'\nsec s():\n  set_standard_digital_out(1, True)\nend\n') == [
        'def p():\n  if True:\n    sleep(1)\n  end\nend\n', 'sec s():\n  set_standard_digital_out(1, True)\nend\n']
    with pytest.raises(ScriptError, match='not UTF-8'):
        reader.feed(b'\xfe\n')
