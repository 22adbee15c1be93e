"""The Dashboard Server's network face (devices/network/dashboard.py) on a real socket, over the arm's core.

The client is written from UR's Dashboard Server document: connect to port
29999 (here a free port on loopback), read the greeting line, send each
command ended by a newline and read one reply line. The robot behind it is
the core as the arm's node builds it (kinematic joints), so the replies and
their effects are the robot's own.
"""
import select
import socket
import threading

import pytest

from ur3_ft_gripper_description.devices import sim_params
from ur3_ft_gripper_description.devices.network import dashboard, listen
from controller_cell import Cell
from test_ur_arm_core import make_core, make_settings


class Client(object):
    """A Dashboard Server client as UR's document describes one."""

    def __init__(self, port, address=listen.LOOPBACK):
        self.socket = socket.create_connection((address, port), timeout=10.0)
        self.lines = self.socket.makefile('rb')
        self.greeting = self.line()

    def line(self):
        return self.lines.readline().decode('ascii').rstrip('\n')

    def send(self, data):
        self.socket.sendall(data)

    def ask(self, command):
        self.send((command + '\n').encode('ascii'))
        return self.line()

    def closed(self):
        """Whether the server closed the connection (end of stream, nothing more sent)."""
        return self.lines.read() == b''

    def close(self):
        self.lines.close()
        self.socket.close()


@pytest.fixture
def served(configured_model):
    """(core, port, log lines) of a Dashboard Server on a free loopback port over a fresh core."""
    core, lock, logged = make_core(configured_model), threading.Lock(), []

    def answer(command):
        with lock:
            return core.dashboard(command)

    server = dashboard.serve(listen.LOOPBACK, answer, logged.append, port=0)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield core, server.server_address[1], logged
    server.shutdown()
    server.server_close()
    thread.join(5.0)


def test_a_client_is_greeted_and_the_robot_answers_and_obeys(served):
    core, port, logged = served
    client = Client(port)
    assert client.greeting == 'Connected: Universal Robots Dashboard Server'
    assert client.ask('robotmode') == 'Robotmode: RUNNING'
    assert client.ask('power off') == 'Powering off'
    assert core.robot.robot_mode == 'POWER_OFF'
    assert client.ask('robotmode') == 'Robotmode: POWER_OFF'
    assert client.ask('power on') == 'Powering on'
    assert client.ask('brake release') == 'Brake releasing'
    assert client.ask('PolyscopeVersion') == 'URSoftware %s' % core.software.version_text
    assert client.ask('safetystatus') == 'Safetystatus: NORMAL'
    assert client.ask('no such command') == "could not understand: 'no such command'"
    assert client.ask('quit') == 'Disconnected'
    assert client.closed()
    client.close()
    assert logged == []


def test_two_clients_at_once_see_one_robot(served):
    core, port, _ = served
    first, second = Client(port), Client(port)
    assert first.ask('power off') == 'Powering off'
    assert second.ask('robotmode') == 'Robotmode: POWER_OFF'
    first.close()
    assert second.ask('safetymode') == 'Safetymode: NORMAL'
    second.close()


def test_a_command_split_across_packets_and_crlf_lines_are_one_command_each(served):
    _, port, _ = served
    client = Client(port)
    client.send(b'robot')
    client.send(b'mode\r\n')
    assert client.line() == 'Robotmode: RUNNING'
    client.send(b'running\nsafetymode\n')
    assert [client.line(), client.line()] == ['Program running: true', 'Safetymode: NORMAL']
    client.close()


@pytest.mark.parametrize('garbage, problem', [
    (b'x' * (dashboard.MAX_LINE + 10), 'a line over %d bytes' % dashboard.MAX_LINE),
    (b'robotmode \xff\xfe\n', 'bytes that are not ASCII text'),
])
def test_bad_input_closes_that_connection_alone_with_one_log_line(served, garbage, problem):
    core, port, logged = served
    bystander, bad = Client(port), Client(port)
    bad.send(garbage)
    assert bad.closed()
    bad.close()
    assert len(logged) == 1 and problem in logged[0] and 'dashboard server: 127.0.0.1:' in logged[0], logged
    assert bystander.ask('robotmode') == 'Robotmode: RUNNING'
    assert Client(port).ask('running') == 'Program running: true'
    bystander.close()


def test_a_client_that_leaves_mid_command_costs_nothing(served):
    _, port, logged = served
    for _ in range(5):
        leaving = Client(port)
        leaving.send(b'power o')
        leaving.socket.close()
        leaving = Client(port)
        leaving.send(b'robotmode\n' * 50)
        leaving.socket.shutdown(socket.SHUT_RDWR)
        leaving.socket.close()
    assert Client(port).ask('robotmode') == 'Robotmode: RUNNING'
    assert logged == []


def test_a_taken_port_is_one_line_naming_the_fix(served):
    _, port, _ = served
    with pytest.raises(listen.ListenError) as caught:
        dashboard.serve(listen.LOOPBACK, lambda command: '', print, port=port)
    text = str(caught.value)
    assert '\n' not in text and '127.0.0.1:%d' % port in text and '127.0.0.2' in text, text


def test_an_address_this_machine_does_not_have_is_one_line_naming_the_fix():
    # 192.0.2.1: TEST-NET-1 (RFC 5737), never a machine's own address.
    with pytest.raises(listen.ListenError) as caught:
        dashboard.serve('192.0.2.1', lambda command: '', print, port=0)
    text = str(caught.value)
    assert '\n' not in text and '192.0.2.1' in text and 'no such address' in text and '127.0.0.1' in text, text


def test_a_second_cell_serves_the_robots_port_on_its_own_loopback_address(served):
    """Linux answers on every 127.x.y.z: two cells each take the same port on their own address."""
    _, port, _ = served
    server = dashboard.serve('127.0.0.2', lambda command: 'second cell', print, port=port)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        assert Client(port, '127.0.0.2').ask('robotmode') == 'second cell'
        assert Client(port).ask('robotmode') == 'Robotmode: RUNNING'
    finally:
        server.shutdown()
        server.server_close()


@pytest.mark.parametrize('value', ['localhost', '192.168.1', '127.0.0.256', 'my robot'])
def test_robot_ip_that_is_not_an_ipv4_address_is_one_line(configured_model, value):
    with pytest.raises(sim_params.ParamError) as caught:
        make_settings(configured_model, **{'~robot_ip': value})
    text = str(caught.value)
    assert '\n' not in text and text.startswith('~robot_ip=') and '127.0.0.1' in text, text


def test_robot_ip_is_off_unless_given(configured_model):
    assert make_settings(configured_model).robot_ip == ''
    assert make_settings(configured_model, **{'~robot_ip': ' 127.0.0.3 '}).robot_ip == '127.0.0.3'


def test_an_idle_client_keeps_its_session_whatever_default_timeout_its_process_set(configured_model):
    # rospy sets a 60 s default timeout on every socket its process makes afterwards, accepted ones included;
    # the controller keeps an idle client's connection for as long as the client keeps it.
    core = make_core(configured_model)
    server = dashboard.serve(listen.LOOPBACK, core.dashboard, [].append, port=0)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    before = socket.getdefaulttimeout()
    socket.setdefaulttimeout(0.2)
    try:
        client = Client(server.server_address[1])
        threading.Event().wait(1.0)  # five of those timeouts, idle
        assert client.ask('robotmode') == 'Robotmode: RUNNING'
        client.close()
    finally:
        socket.setdefaulttimeout(before)
        server.shutdown()
        server.server_close()
        thread.join(5.0)


def test_stop_replies_once_the_faces_have_sent_the_cycle_that_carries_it(configured_model):
    # UR's document (CB3 3.3 on, every e-Series): play, stop, pause and load return when done, so a client
    # reading RTDE after "Stopped" (ur_rtde does, 0.1 s later) finds the program stopped.
    cell = Cell(configured_model, 'ur5e')
    try:
        client = Client(cell.faces.port('dashboard'))
        assert client.ask('robotmode') == 'Robotmode: RUNNING'  # a query answers at once, with no cycle
        assert cell.core.robot.program_state == 'PLAYING'  # External Control, as the cell starts
        client.send(b'stop\n')
        assert select.select([client.socket], [], [], 0.3)[0] == []  # no cycle yet, no reply
        cell.step()
        assert client.line() == 'Stopped'
        assert cell.core.robot.program_state == 'STOPPED'
        client.close()
    finally:
        cell.faces.shutdown()
