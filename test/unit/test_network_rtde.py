"""RTDE's network face (devices/network/rtde.py) on a real socket, over the arm's core and its cycles.

The client (ur3_ft_gripper_testing.rtde_client) is written from UR's RTDE
guide. The robot behind the face is the core as the arm's node builds it
(kinematic joints); the test steps it as the node does, the face seeing
each cycle, so what a client reads is checked against what the robot did:
where a program moved the joints, what it wrote to a register.
"""
import socket

import numpy as np
import pytest

from ur3_ft_gripper_description.devices.network import listen, rtde
from ur3_ft_gripper_description.devices.ur_arm import rtde_fields
from ur3_ft_gripper_description.devices.ur_arm.software import TABLE_KEYS
from ur3_ft_gripper_description.number_text import number_list
from ur3_ft_gripper_testing.rtde_client import RtdeClient
from controller_cell import Cell, rtde_max_frequency

TARGET = [0.3, -1.4, 1.3, -1.5, -1.5, 0.4]


@pytest.fixture(params=['ur5e', 'ur3'])
def cell(request, configured_model):
    cell = Cell(configured_model, request.param)
    yield cell
    cell.faces.shutdown()


def test_the_controller_answers_with_its_version_and_takes_protocol_1_and_2(cell):
    client = RtdeClient(cell.port)
    assert client.negotiate(3) is False
    assert client.negotiate(2) is True
    assert client.controller_version() == cell.core.software.version
    assert client.negotiate(1) is True
    client.close()


def test_a_recipe_is_answered_with_the_guides_types_and_an_unknown_name_is_not_found(cell):
    client = cell.client()
    recipe = client.setup_outputs(['timestamp', 'actual_q', 'robot_mode', 'no_such_field'], 125)
    assert recipe.types == ['DOUBLE', 'VECTOR6D', 'INT32', 'NOT_FOUND'] and recipe.id == 0
    assert client.start() is False  # no valid output recipe
    recipe = client.setup_outputs(['timestamp', 'actual_q', 'robot_mode'], 125)
    assert recipe.id == 1 and recipe.ok
    client.close()


def test_the_frequency_is_the_controllers_at_most(cell):
    client = cell.client()
    fastest = rtde_max_frequency(cell.core)
    assert client.setup_outputs(['timestamp'], fastest * 2).id == 0
    assert client.setup_outputs(['timestamp'], fastest).id == 1
    client.close()


def test_data_comes_at_the_asked_frequency_on_the_controllers_clock(cell):
    client = cell.client()
    client.setup_outputs(['timestamp', 'actual_q'], 25.0)
    assert client.start()
    seconds = 2.0
    cell.step(int(round(seconds / cell.dt)))
    stamps = [client.data()['timestamp'] for _ in range(int(25 * seconds))]
    assert np.allclose(np.diff(stamps), 1.0 / 25, atol=1e-9)
    assert stamps[0] == pytest.approx(cell.dt, abs=1e-12)  # the first cycle after the start
    client.close()


def test_a_client_reads_where_a_program_moved_the_joints(cell):
    client = cell.client()
    client.setup_outputs(['timestamp', 'actual_q', 'target_q', 'actual_TCP_pose', 'runtime_state'],
                         rtde_max_frequency(cell.core))
    assert client.start()
    with cell.lock:
        cell.core.script_command('movej([%s], a=3, v=2)' % number_list(TARGET))
    cell.step()
    assert client.data()['runtime_state'] == rtde_fields.RUNTIME_STATE['PLAYING']
    for _ in range(int(5.0 / cell.dt)):
        cell.step()
        last = client.data()
        if last['runtime_state'] == rtde_fields.RUNTIME_STATE['STOPPED']:
            break
    assert last['actual_q'] == pytest.approx(TARGET, abs=1e-6)
    assert last['target_q'] == pytest.approx(TARGET, abs=1e-6)
    with cell.lock:
        pose = cell.core.script_robot.call('get_actual_tcp_pose', [], {})
    assert last['actual_TCP_pose'] == pytest.approx(list(pose), abs=1e-9)
    client.close()


def test_a_pause_stops_the_data_and_a_start_resumes_it(cell):
    client = cell.client()
    client.setup_outputs(['timestamp'], rtde_max_frequency(cell.core))
    assert client.start()
    cell.step(3)
    assert client.pause()
    cell.step(50)
    # Had data packages come while paused, they would stand before the start's reply.
    assert client.start()
    cell.step(1)
    assert client.data()['timestamp'] == pytest.approx(54 * cell.dt, abs=1e-9)
    client.close()


def test_a_program_reads_the_registers_a_client_writes_and_the_client_reads_what_it_wrote_back(cell):
    writer, reader = cell.client(), cell.client()
    inputs = writer.setup_inputs(['input_int_register_0', 'input_double_register_5', 'input_bit_register_64'])
    assert inputs.id == 1 and inputs.types == ['INT32', 'DOUBLE', 'BOOL']
    # An input another client writes is not to be had; the writer may set it up again.
    assert reader.setup_inputs(['input_int_register_0']).types == ['IN_USE']
    assert writer.setup_inputs(['input_int_register_0']).id == 2
    reader.setup_outputs(['output_int_register_1', 'output_double_register_1', 'output_bit_register_65',
                          'input_int_register_0', 'runtime_state'], 125)
    writer.write(inputs, {'input_int_register_0': -41, 'input_double_register_5': 2.5, 'input_bit_register_64': True})
    writer.controller_version()  # a reply after the data package: the package has been taken
    with cell.lock:
        cell.core.script_command('def p():\n'
                                 '  write_output_integer_register(1, read_input_integer_register(0) - 1)\n'
                                 '  write_output_float_register(1, read_input_float_register(5) * 2)\n'
                                 '  write_output_boolean_register(65, not read_input_boolean_register(64))\n'
                                 'end\n')
    cell.step(100)
    assert reader.start()
    cell.step(int(round(1.0 / 125 / cell.dt)))
    values = reader.data()
    assert values['input_int_register_0'] == -41
    assert values['output_int_register_1'] == -42
    assert values['output_double_register_1'] == 5.0
    assert values['output_bit_register_65'] is False
    writer.close()
    reader.close()


def test_a_client_that_closed_its_connection_leaves_its_inputs_to_the_next_before_its_session_ends(cell):
    # The closed client's session is held here, not served by a thread, so that it cannot have ended: only
    # its connection tells that no more comes from it.
    names = ['input_int_register_0', 'input_double_register_0']
    with socket.create_server((listen.LOOPBACK, 0)) as server:
        client = socket.create_connection(server.getsockname())
        served, _ = server.accept()
    closed = cell.faces.rtde.session(lambda data: None, 'a client', lambda: listen.peer_hung_up(served))
    try:
        assert cell.faces.rtde.claim_inputs(closed, names)[1]
        follower = cell.client()
        assert follower.setup_inputs(names).types == ['IN_USE', 'IN_USE']  # while its client is there
        client.sendall(rtde.packet(rtde.PAUSE))  # as ur_rtde disconnects: unread when it closes
        client.close()
        assert follower.setup_inputs(names).types == ['INT32', 'DOUBLE']
        follower.close()
    finally:
        served.close()


def test_clients_that_take_the_same_inputs_one_after_the_other_each_get_them(cell):
    names = ['speed_slider_mask', 'speed_slider_fraction', 'input_int_register_0']
    for _ in range(20):
        client = cell.client()
        assert client.setup_inputs(names).ok
        assert client.pause()
        client.close()


def test_the_speed_slider_and_the_digital_outputs_follow_their_masks(cell):
    client = cell.client()
    inputs = client.setup_inputs(['speed_slider_mask', 'speed_slider_fraction', 'standard_digital_output_mask',
                                  'standard_digital_output'])
    client.write(inputs, {'speed_slider_mask': 1, 'speed_slider_fraction': 0.25,
                          'standard_digital_output_mask': 0b101, 'standard_digital_output': 0b001})
    client.controller_version()
    with cell.lock:
        assert cell.core.robot.speed_slider == 0.25
        assert cell.core.robot.digital_out[:3] == [True, False, False]
    client.write(inputs, {'speed_slider_mask': 0, 'speed_slider_fraction': 0.75,
                          'standard_digital_output_mask': 0b100, 'standard_digital_output': 0b100})
    client.controller_version()
    with cell.lock:
        assert cell.core.robot.speed_slider == 0.25  # not in the mask: unchanged
        assert cell.core.robot.digital_out[:3] == [True, False, True]
    client.close()


def test_protocol_1_has_no_recipe_ids_and_runs_at_the_controllers_rate(cell):
    client = cell.client(protocol=1)
    reply = client.ask('O', b'timestamp,actual_q')
    assert reply == b'DOUBLE,VECTOR6D'  # the types alone
    assert client.start()
    cell.step(2)
    kind, payload = client.receive()
    assert kind == 'U' and len(payload) == 8 + 48  # no recipe id
    client.close()


@pytest.mark.parametrize('garbage, problem', [
    (b'\x00\x03X', 'unknown type'),
    (b'\x00\x01V', 'header of size 1'),
    (b'\x00\x04V\x01', 'cannot read'),
])
def test_bad_input_costs_the_client_its_connection_with_one_line_and_the_robot_goes_on(cell, garbage, problem):
    good = cell.client()
    good.setup_outputs(['timestamp'], 125)
    assert good.start()
    bad = socket.create_connection(('127.0.0.1', cell.port), timeout=10)
    bad.sendall(garbage)
    assert bad.recv(100) == b''  # closed by the controller
    bad.close()
    cell.step(int(round(1.0 / 125 / cell.dt)))
    assert good.data()['timestamp'] > 0
    assert len(cell.logged) == 1 and problem in cell.logged[0] and 'connection is closed' in cell.logged[0]
    good.close()


@pytest.mark.parametrize('generation, version', [('e_series', (5, 99, 0, 0)), ('cb3', (3, 99, 0, 0))])
def test_every_output_field_of_the_guide_has_a_value_of_the_twin(generation, version):
    fields = rtde.read_table(generation, version)['outputs']
    assert [name for name in fields if rtde_fields.reader(name) is None] == []


def test_each_generation_serves_the_fields_of_its_version(cell):
    version, generation = cell.core.software.version, cell.core.software.generation
    fields = rtde.read_table(TABLE_KEYS[generation], version)['outputs']
    client = cell.client()
    newest_only = 'target_gravity'  # 5.26 on: the simulated e-Series runs older software
    assert newest_only not in fields
    assert client.setup_outputs([newest_only], 125).types == ['NOT_FOUND']
    served = sorted(fields)
    recipe = client.setup_outputs(served[:60], 125)
    assert recipe.ok and recipe.types == [fields[name] for name in served[:60]]
    client.close()


def test_a_client_that_does_not_read_loses_its_connection_and_the_others_go_on(cell):
    reader, sleeper = cell.client(), cell.client()
    reader.setup_outputs(['timestamp'], 125)
    sleeper.setup_outputs(['actual_q'] * 100, rtde_max_frequency(cell.core))  # 4.8 kB a cycle, never read
    assert reader.start() and sleeper.start()
    every = int(round(1.0 / 125 / cell.dt))
    for _ in range(2000):
        cell.step(every)
        reader.data()
        if cell.logged:
            break
    assert len(cell.logged) == 1 and 'reads slower than the frequency it asked for' in cell.logged[0]
    with pytest.raises(EOFError):
        while True:
            sleeper.receive()
    cell.step(every)
    assert reader.data()['timestamp'] > 0
    reader.close()
    sleeper.close()


def test_the_elbow_moves_as_its_velocity_says(cell):
    client = cell.client()
    client.setup_outputs(['timestamp', 'elbow_position', 'elbow_velocity', 'actual_TCP_pose', 'actual_TCP_speed'],
                         rtde_max_frequency(cell.core))
    assert client.start()
    with cell.lock:
        cell.core.script_command('speedj([0.3, -0.2, 0.25, 0, 0, 0], 5.0, 2.0)')
    cycles = int(round(1.0 / cell.dt))
    cell.step(cycles)  # at speed by the end
    earlier, later = [client.data() for _ in range(cycles)][-2:]
    dt = later['timestamp'] - earlier['timestamp']
    for position, velocity in (('elbow_position', 'elbow_velocity'), ('actual_TCP_pose', 'actual_TCP_speed')):
        moved = (np.array(later[position][:3]) - np.array(earlier[position][:3])) / dt
        assert np.linalg.norm(moved) > 0.05  # it moves
        assert moved == pytest.approx(later[velocity][:3], abs=2e-3), position
    client.close()
