"""The 2F-140 on the gripper URCap's socket (devices/network/robotiq_urcap.py), on a real socket, over the register
machine the gripper node runs (kinematic fingers, no master).

The client is written from the protocol as the URCap's clients speak it (ur_rtde's robotiq_gripper
example): "SET <VAR> <value> ..." answered b"ack", "GET <VAR>" answered "<VAR> <value>". It activates the
gripper as that example does (reset, then ACT 1 until STA 3), closes on an object (OBJ 2 at the object's
width), opens, and reads a fault; time passes in the register machine between its requests, as the node's
loop lets it.
"""
import socket
import threading

import pytest

from ur3_ft_gripper_description.devices import gripper_sim
from ur3_ft_gripper_description.devices.network import listen, robotiq_urcap
from test_sim_nodes import SPEC, gripper

OBJECT_WIDTH = 0.06  # m between the pads


class UrcapClient(object):
    def __init__(self, port):
        self.socket = socket.create_connection((listen.LOOPBACK, port), timeout=10.0)

    def set(self, **values):
        self.socket.sendall(('SET' + ''.join(' %s %d' % item for item in values.items()) + '\n').encode('ascii'))
        return self.socket.recv(1024)

    def get(self, name):
        self.socket.sendall(('GET %s\n' % name).encode('ascii'))
        reply_name, value = self.socket.recv(1024).decode('ascii').split()
        assert reply_name == name
        return int(value)

    def close(self):
        self.socket.close()


@pytest.fixture
def urcap():
    """(client, register machine, advance(seconds), log lines) of a URCap socket on a free loopback port."""
    machine, _, _ = gripper(object_width=OBJECT_WIDTH)
    lock, logged = threading.Lock(), []
    server = gripper_sim.start_urcap_socket(listen.LOOPBACK, machine, lock, logged.append, port=0)

    def advance(seconds, dt=0.02):
        for _ in range(int(round(seconds / dt))):
            with lock:
                machine.advance(dt)

    client = UrcapClient(server.server_address[1])
    yield client, machine, advance, logged
    client.close()
    server.shutdown()
    server.server_close()


def test_a_client_activates_closes_on_an_object_and_opens_as_ur_rtdes_example_does(urcap):
    client, machine, advance, logged = urcap
    assert client.set(ACT=0, ATR=0) == b'ack'  # reset
    assert (client.get('ACT'), client.get('STA')) == (0, 0)
    assert client.set(ACT=1) == b'ack'
    advance(SPEC.activation_time + 0.1)
    assert (client.get('ACT'), client.get('STA')) == (1, 3)
    # Close at full speed and a middle force, in one SET, as the example's move() sends it.
    assert client.set(POS=255, SPE=255, FOR=128, GTO=1) == b'ack'
    assert (client.get('PRE'), client.get('SPE'), client.get('FOR'), client.get('GTO')) == (255, 255, 128, 1)
    advance(3.0)
    assert client.get('OBJ') == 2  # stopped on an object while closing
    # The fingers stand at the object's width, in the unit's register scale.
    assert client.get('POS') == pytest.approx(SPEC.scale.position(OBJECT_WIDTH), abs=1)
    # What the ROS face would publish is the same register.
    assert machine.status()['gPO'] == client.get('POS') and machine.status()['gOBJ'] == 2
    assert client.set(POS=0) == b'ack'
    advance(3.0)
    assert (client.get('OBJ'), client.get('POS')) == (3, round(SPEC.scale.position(SPEC.stroke)))
    assert logged == []


def test_the_automatic_release_reads_its_faults_as_the_manual_gives_them(urcap):
    client, _, advance, _ = urcap
    client.set(ACT=1)
    advance(SPEC.activation_time + 0.1)
    client.set(POS=255, SPE=255, FOR=128, GTO=1)
    advance(3.0)
    assert client.set(ATR=1, ARD=0) == b'ack'  # ARD is accepted: the simulated release always opens
    assert client.get('FLT') == gripper_sim.FAULT_AUTO_RELEASE_ACTIVE
    advance(10.0)
    assert client.get('FLT') == gripper_sim.FAULT_AUTO_RELEASE_DONE


@pytest.mark.parametrize('line, problem', [
    (b'HELLO\n', 'not a command'),
    (b'GET XYZ\n', 'GET takes one of'),
    (b'SET POS\n', 'SET takes pairs'),
    (b'SET POS 300\n', 'whole number 0..255'),
    (b'SET POS -1\n', 'whole number 0..255'),
    (b'SET MOV 1\n', 'SET MOV: not one of'),
])
def test_bad_input_is_one_log_line_no_reply_and_the_next_command_is_answered(urcap, line, problem):
    client, machine, _, logged = urcap
    before = dict(machine.command)
    client.socket.sendall(line)
    assert client.get('ACT') == 0  # the next command's reply is the first that comes back
    assert len(logged) == 1 and problem in logged[0] and 'gripper URCap socket: 127.0.0.1:' in logged[0], logged
    assert machine.command == before


def test_a_set_is_atomic_a_bad_pair_writes_none_of_the_line(urcap):
    client, machine, _, logged = urcap
    client.socket.sendall(b'SET ACT 1 POS 999\n')
    assert client.get('ACT') == 0 and machine.command['rACT'] == 0
    assert len(logged) == 1


def test_the_port_and_the_variables_are_the_tables():
    table = robotiq_urcap.read_table()
    assert table['port'] == 63352
    assert set(table['set']) == {'ACT', 'GTO', 'ATR', 'ARD', 'POS', 'SPE', 'FOR'}
    registers = set(gripper_sim.COMMAND_FIELDS)
    assert {r for r in table['set'].values() if r is not None} <= registers
    status = set(gripper(object_width=None)[0].status())
    assert all(r in status or r in registers for r in table['get'].values())


def test_a_taken_address_is_one_line():
    machine, _, _ = gripper()
    first = gripper_sim.start_urcap_socket(listen.LOOPBACK, machine, threading.Lock(), print, port=0)
    try:
        with pytest.raises(listen.ListenError) as caught:
            gripper_sim.start_urcap_socket(listen.LOOPBACK, machine, threading.Lock(), print,
                                           port=first.server_address[1])
        assert 'gripper URCap socket cannot listen' in str(caught.value) and '\n' not in str(caught.value)
    finally:
        first.shutdown()
        first.server_close()
