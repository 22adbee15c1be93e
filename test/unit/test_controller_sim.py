"""ur_controller_sim, the simulated controller without ROS, as users start it (rosrun), on real sockets.

A process of its own on a loopback address of its own; the clients are the
tests' own, written from UR's documents (RTDE, Dashboard Server). No ROS
master runs: the controller needs none.
"""
import random
import socket
import subprocess
import time

import pytest

from ur3_ft_gripper_testing.rtde_client import RtdeClient
from test_network_dashboard import Client as DashboardClient

COME_UP = 60.0  # wall s for the process to expand the model and listen
PORTS = (29999, 30001, 30002, 30003, 30004, 30011, 30012, 30013)


def start(*args):
    return subprocess.Popen(['rosrun', 'ur3_ft_gripper_description', 'ur_controller_sim'] + list(args),
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)


@pytest.fixture(scope='module')
def controller():
    address = '127.0.%d.%d' % (random.randint(1, 254), random.randint(2, 254))
    process = start('--ur-type', 'ur3', '--robot-ip', address)
    deadline = time.monotonic() + COME_UP
    try:
        while True:
            try:
                socket.create_connection((address, PORTS[-1]), timeout=1.0).close()
                break
            except OSError:
                assert process.poll() is None, process.stdout.read()
                assert time.monotonic() < deadline, 'ur_controller_sim did not listen within %g s' % COME_UP
                time.sleep(0.2)
        yield address
    finally:
        process.terminate()
        process.wait(timeout=30)


def test_every_interface_listens_on_the_robots_ports(controller):
    for port in PORTS:
        socket.create_connection((controller, port), timeout=10.0).close()


def test_it_starts_as_a_robot_without_its_driver_powered_and_its_program_loaded_not_playing(controller):
    # As a client finds a robot whose driver has not started External Control: ur_rtde then sends its own
    # program at once, rather than first waiting for one that never answers it.
    dashboard = DashboardClient(29999, controller)
    answers = [dashboard.ask(command) for command in ('robotmode', 'programState')]
    dashboard.close()
    assert answers == ['Robotmode: RUNNING', 'STOPPED external_control.urp']


def test_the_controller_steps_at_its_rate_and_a_program_moves_the_arm(controller):
    client = RtdeClient(30004, controller)
    assert client.negotiate(2)
    assert client.controller_version()[0] == 3  # the ur3 is a CB3
    client.setup_outputs(['timestamp', 'actual_q', 'runtime_state'], 125)
    assert client.start()
    stamps = [client.data()['timestamp'] for _ in range(20)]
    # A cycle of 8 ms each: the controller's own period, whatever the wall clock's jitter.
    assert [b - a for a, b in zip(stamps, stamps[1:])] == pytest.approx([0.008] * 19, abs=1e-9)
    target = [0.2, -1.4, 1.3, -1.5, -1.5, 0.3]
    with socket.create_connection((controller, 30002), timeout=10.0) as secondary:
        secondary.sendall(('def from_client():\n  movej([%s], a=3, v=2)\nend\n'
                           % ', '.join(repr(v) for v in target)).encode())
        end = None
        while True:
            data = client.data()
            if data['runtime_state'] == 2 and end is None:
                end = data['timestamp'] + 5.0  # s of the controller's time for the move
            if end is not None and data['runtime_state'] == 1:
                break
            assert end is None or data['timestamp'] < end, 'the program did not end within 5 s'
    assert data['actual_q'] == pytest.approx(target, abs=1e-6)
    client.close()


@pytest.mark.parametrize('args, problem', [
    (['--ur-type', 'ur9'], "'ur9' is not a UR model"),
    (['--robot-ip', 'robot.local'], 'is not an IPv4 address'),
    (['--robot-ip', '10.255.255.1'], 'this machine has no such address'),
    (['--kinematics-params', '/no/such/calibration.yaml'], 'there is no file /no/such/calibration.yaml'),
])
def test_bad_input_is_one_line_and_exit_status_1(args, problem):
    process = start(*args)
    out, _ = process.communicate(timeout=COME_UP)
    assert process.returncode == 1
    lines = out.strip().splitlines()
    assert len(lines) == 1 and problem in lines[0], out
