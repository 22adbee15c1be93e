"""URScript's socket_* functions against a real TCP server on loopback, as the URScript manual defines them.

The robot is the client; the server here is a peer written for each test.
What the program read comes back through textmsg, in the robot's log.
"""
import math
import socket
import struct
import threading
import time

import pytest

from ur3_ft_gripper_description.devices import sim_params

from test_ur_arm_core import make_core

TAKE_IN = 30.0  # wall s for the peer's thread to accept and read


class Peer(object):
    """A one-connection TCP server on loopback; `script(connection)` runs in its thread once the robot is in."""

    def __init__(self, script):
        self.listener = socket.socket()
        self.listener.bind(('127.0.0.1', 0))
        self.listener.listen(1)
        self.port = self.listener.getsockname()[1]
        self.received = b''
        self.thread = threading.Thread(target=self._serve, args=(script,), daemon=True)
        self.thread.start()

    def _serve(self, script):
        self.listener.settimeout(TAKE_IN)
        connection, _ = self.listener.accept()
        connection.settimeout(TAKE_IN)
        with connection:
            script(self, connection)

    def read_until(self, connection, ending):
        while not self.received.endswith(ending):
            self.received += connection.recv(4096)

    def close(self):
        self.listener.close()


def run_program(arm, program, seconds=30.0):
    """Run `program` to its end, the cell paced to the wall clock (real_time_factor 1) so that the peer's
    thread has the time a peer on the network has; the controller's time bounded by `seconds`. The
    robot's log lines the program wrote."""
    logged = len(arm.robot.log)
    arm.script_command(program)
    errors = [text for level, text in arm.take_messages() if level == 'error']
    assert not errors, errors
    cycles, began = 0, time.monotonic()
    while arm.script_running:
        assert cycles * 0.002 < seconds, 'the program did not end within %g s' % seconds
        arm.step(0.002)
        cycles += 1
        ahead = began + cycles * 0.002 - time.monotonic()
        if ahead > 0:
            time.sleep(ahead)
    errors = [text for level, text in arm.take_messages() if level == 'error']
    assert not errors, errors
    return list(arm.robot.log)[logged:]


@pytest.fixture
def arm(configured_model):
    return make_core(configured_model)


def test_a_program_talks_to_a_peer_in_every_format_the_manual_reads(arm):
    def peer(self, connection):
        self.read_until(connection, b'hello\n')
        connection.sendall(struct.pack('>3i', 7, -2, 100000))
        connection.sendall(b'(1.5, -2.25, 3)')
        connection.sendall(bytes([1, 2, 255]))
        connection.sendall(b'noise<start>payload<end>rest\n')
        self.read_until(connection, b'GET speed\n')
        connection.sendall(b'speed 42\n')
        self.read_until(connection, b'SET gain 3\n')
        connection.sendall(struct.pack('>i', 5))

    server = Peer(peer)
    log = run_program(arm, 'def talk():\n'
                           '  textmsg(socket_open("127.0.0.1", %d, "cam"))\n'
                           '  textmsg(socket_send_line("hello", "cam"))\n'
                           '  textmsg(socket_read_binary_integer(3, "cam"))\n'
                           '  textmsg(socket_read_ascii_float(3, "cam"))\n'
                           '  textmsg(socket_read_byte_list(3, "cam"))\n'
                           '  textmsg(socket_read_string("cam", prefix="<start>", suffix="<end>"))\n'
                           '  textmsg(socket_read_line("cam"))\n'
                           '  textmsg(socket_get_var("speed", "cam"))\n'
                           '  socket_set_var("gain", 3, "cam")\n'
                           '  textmsg(socket_read_binary_integer(1, "cam", timeout=0))\n'
                           '  socket_close("cam")\n'
                           'end\n' % server.port)
    server.close()
    assert log == ['True', 'True', '[3, 7, -2, 100000]', '[3, 1.5, -2.25, 3]', '[3, 1, 2, 255]', 'payload',
                   'rest', '42', '[1, 5]']


def test_a_read_that_times_out_gives_the_manuals_failure_in_the_controllers_time(arm):
    def peer(self, connection):
        self.read_until(connection, b'done\n')  # says nothing until the program is over

    server = Peer(peer)
    started = arm.uptime
    log = run_program(arm, 'def wait():\n'
                           '  socket_open("127.0.0.1", %d)\n'
                           '  textmsg(socket_read_binary_integer(2, timeout=0.5))\n'
                           '  textmsg(socket_read_ascii_float(2, timeout=0.5))\n'
                           '  textmsg(socket_read_string(timeout=0.5))\n'
                           '  socket_send_line("done")\n'
                           'end\n' % server.port)
    server.close()
    assert log == ['[0, -1, -1]', '[0, nan, nan]', '']
    assert arm.uptime - started == pytest.approx(1.5, abs=0.05)  # three reads of 0.5 s each


def test_a_socket_nobody_listens_on_does_not_open_and_its_calls_fail(arm):
    probe = socket.socket()
    probe.bind(('127.0.0.1', 0))
    port = probe.getsockname()[1]
    probe.close()  # a port nobody listens on
    log = run_program(arm, 'def refused():\n'
                           '  textmsg(socket_open("127.0.0.1", %d))\n'
                           '  textmsg(socket_send_string("x"))\n'
                           '  textmsg(socket_read_byte_list(2, timeout=0.1))\n'
                           'end\n' % port)
    assert log == ['False', 'False', '[0, -1, -1]']


def test_bad_arguments_stop_the_program_naming_them(arm):
    for call, problem in (('socket_send_byte(256)', 'from 0 to 255'),
                          ('socket_read_binary_integer(31)', 'from 1 to 30'),
                          ('socket_open(1, 2)', 'address must be a string')):
        arm.script_command('def bad():\n  %s\nend\n' % call)
        for _ in range(3):
            arm.step(0.002)
        level, text = arm.take_messages()[-1]
        assert level == 'error' and problem in text, text
    assert not math.isnan(arm.uptime)


OUTSIDE = 'def out():\n  textmsg(socket_open("192.0.2.7", 30002))\nend\n'  # TEST-NET-1: no such host anywhere


def test_an_address_beyond_loopback_is_the_robots_runtime_error_naming_it(arm):
    arm.script_command(OUTSIDE)
    for _ in range(3):
        arm.step(0.002)
    level, text = arm.take_messages()[-1]
    assert level == 'error' and text == (
        'script_command: RuntimeException: Runtime error in line 2, column 11 Error: socket_open: 192.0.2.7 is beyond '
        'this machine; the simulated robot connects to loopback and to the addresses you allow it '
        '(script_socket_hosts:=192.0.2.7); program stopped')
    assert not arm.script_running


def test_a_network_the_user_allows_is_tried_as_the_robot_tries_it(configured_model):
    arm = make_core(configured_model, **{'~script_socket_hosts': '10.1.2.3, 192.0.2.0/24'})
    log = run_program(arm, OUTSIDE, seconds=5.0)
    assert log == ['False']  # allowed, and nobody answers there within socket_open's 2 s


@pytest.mark.parametrize('value', ['192.0.2.0/33', 'robot.local', '::1'])
def test_a_bad_allowance_is_one_line_naming_it(configured_model, value):
    with pytest.raises(sim_params.ParamError) as caught:
        make_core(configured_model, **{'~script_socket_hosts': value})
    assert str(caught.value).startswith('~script_socket_hosts=%s: %r is not an IPv4 address or network' % (value, value))
    assert '\n' not in str(caught.value)
