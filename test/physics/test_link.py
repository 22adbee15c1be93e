"""The link between the cell (the arm's process) and the FT 300 and 2F-140 nodes' processes."""
import itertools
import json
import os
import stat
import subprocess
import sys
import time

import numpy as np
import pytest

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices.physics.link import VERSION, CellClient, CellServer, LinkError
from ur3_ft_gripper_description.model import inertials
from ur3_ft_gripper_testing.physics import START, STANDARD_GRAVITY, Served

# A node's side, in a process of its own: hello, the wrench, then close the fingers and wait.
NODE = '''
import json, sys, time
from ur3_ft_gripper_description.devices.physics.link import CellClient
client = CellClient(sys.argv[1], authkey=b'key')
out = {'info': client.info, 'wrench': client.wrench()}
client.finger(0.0, 0.15, 60.0)
deadline = time.monotonic() + 60.0
while time.monotonic() < deadline:
    stamp, state = client.finger()
    if state['motion'] != 'moving':
        break
    time.sleep(0.01)
out['finger'] = state
print(json.dumps(out))
'''


@pytest.fixture
def served(make_cell, between_pads, tmp_path):
    cell = make_cell(between_pads(0.05, mass=0.3), START)
    served = Served(cell, str(tmp_path / 'link' / 'cell.sock'), authkey=b'key')
    yield cell, served.server
    served.close()


def test_a_node_process_reads_the_wrench_and_grasps_through_the_link(served):
    cell, server = served
    run = subprocess.run([sys.executable, '-c', NODE, server.path], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True, timeout=120)
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    assert out['info']['ft_frame'] == 'robotiq_ft_frame_id'
    assert out['info']['gripper']['grip_force_range'] == [10.0, 125.0]
    stamp, wrench, acceleration = out['wrench']
    assert stamp >= 0.0 and wrench[2] == pytest.approx(0.975 * 9.80665, rel=0.02)  # the 2F-140 hanging
    assert np.linalg.norm(acceleration) == pytest.approx(9.80665, rel=0.01)  # held still: 1 g
    assert out['finger']['motion'] == 'on_object'
    assert out['finger']['opening'] == pytest.approx(0.05, abs=0.001)
    with server.lock:
        assert cell.finger().motion == 'on_object'


def test_a_wrong_key_or_request_is_refused_in_one_line(served):
    cell, server = served
    with pytest.raises(LinkError) as raised:
        CellClient(server.path, authkey=b'wrong')
    assert 'refused this key' in str(raised.value)
    client = CellClient(server.path, authkey=b'key')
    with pytest.raises(LinkError) as raised:
        client._ask('teleport', 1.0)
    assert 'unknown request' in str(raised.value) and '\n' not in str(raised.value)
    assert client.wrench()[1][2] > 0  # the link still serves
    client.close()


def sample_timesteps(samples, timestep):
    return [int(round(t / timestep)) for t, _, _ in samples]


def test_the_ft_node_receives_every_wrench_sample_once_however_late_it_asks(served, robot):
    """The FT 300's node asks for the 10 ms samples now and then, as late as its process runs, while the
    arm's loop steps the cell in 8 ms cycles: one sample per 10 ms of simulated time, stamped exactly
    there, none lost or twice, each the hanging 2F-140's weight (the URDF's masses)."""
    cell, server = served
    client = CellClient(server.path, authkey=b'key')
    timestep = client.info['timestep']
    assert timestep == cell.timestep
    deadline = time.monotonic() + 120.0  # only against a cell that stopped: the loops end on simulated time
    while client.wrench()[0] < 1.0 and time.monotonic() < deadline:
        time.sleep(0.01)  # the arm at rest at its start pose
    started, samples, dropped = client.wrench_samples(0.01)  # starts the keeping: none yet
    assert samples == [] and dropped == 0
    kept, now, waits = [], started, itertools.cycle([0.0, 0.013, 0.002, 0.031])
    while now < started + 1.0 and time.monotonic() < deadline:
        time.sleep(next(waits))
        now, samples, dropped = client.wrench_samples(0.01)
        assert dropped == 0
        kept += samples
    first = (int(round(started / timestep)) // 5 + 1) * 5
    steps = sample_timesteps(kept, timestep)
    assert steps == list(range(first, steps[-1] + 1, 5)) and len(steps) >= 100
    assert [t for t, _, _ in kept] == [n * timestep for n in steps]
    assert kept[-1][0] <= now < kept[-1][0] + 0.01
    mass, _ = inertials.mass_below(kinematics.Model(robot[1]), client.info['ft_frame'])
    assert all(wrench[2] == pytest.approx(mass * STANDARD_GRAVITY, rel=0.005) for _, wrench, _ in kept)
    # The sensor points down, held still: its accelerometer reads gravity's reaction along its -z.
    assert all(np.allclose(acceleration, (0.0, 0.0, -STANDARD_GRAVITY), atol=0.01 * STANDARD_GRAVITY)
               for _, _, acceleration in kept)
    # Another period starts the keeping anew at it.
    started, samples, dropped = client.wrench_samples(0.02)
    assert samples == [] and dropped == 0
    kept = []
    while now < started + 0.1 and time.monotonic() < deadline:
        now, samples, dropped = client.wrench_samples(0.02)
        kept += samples
    first = (int(round(started / timestep)) // 10 + 1) * 10
    steps = sample_timesteps(kept, timestep)
    assert steps == list(range(first, steps[-1] + 1, 10)) and len(steps) >= 5
    client.close()


def test_a_wrench_sample_period_of_no_whole_number_of_timesteps_is_refused_in_one_line(served):
    cell, server = served
    client = CellClient(server.path, authkey=b'key')
    with pytest.raises(LinkError) as raised:
        client.wrench_samples(0.003)
    assert '0.003' in str(raised.value) and '0.002' in str(raised.value) and '\n' not in str(raised.value)
    assert client.wrench_samples(0.01)[2] == 0  # the link still serves
    for period in (0.0, -0.02, float('nan')):
        with pytest.raises(LinkError) as raised:
            client.finger_samples(period)
        assert 'finger sample period' in str(raised.value) and '\n' not in str(raised.value)
    _, samples, dropped, now = client.finger_samples(0.02)
    assert (samples, dropped) == ([], 0) and now['motion'] in ('moving', 'at_target', 'on_object')  # kept from now
    with pytest.raises(LinkError) as raised:
        client._ask('hello', VERSION - 1)
    assert 'link version %d' % VERSION in str(raised.value)
    client.close()


def test_no_cell_is_one_line(tmp_path):
    with pytest.raises(LinkError) as raised:
        CellClient(str(tmp_path / 'nothing.sock'))
    assert 'no physics cell at' in str(raised.value) and '\n' not in str(raised.value)


def test_the_truth_is_mujocos_own(served):
    cell, server = served
    client = CellClient(server.path, authkey=b'key')
    stamp, truth = client.truth()
    with server.lock:
        assert truth['objects']['held'][0] == pytest.approx(tuple(cell.object_pose('held')[0]), abs=1e-3)
        assert truth['arm_position'] == pytest.approx(tuple(cell.arm_position), abs=1e-3)
        assert truth['contact_impulse'] == pytest.approx(tuple(cell.contact_impulse()), abs=1e-9)
    assert sorted(truth) == ['arm_position', 'contact_force', 'contact_impulse', 'finger', 'gripper_base', 'objects']
    assert len(truth['gripper_base'][1]) == 3 and truth['finger']['motion'] in ('moving', 'at_target')
    client.close()


def test_the_address_names_the_master_and_the_arm_node_and_its_folder_is_private(tmp_path):
    from ur3_ft_gripper_description.devices.physics.link import cell_address
    home = str(tmp_path)
    one = cell_address('11311 4242', '/ur_hardware_interface', home)
    assert one == cell_address('11311 4242', '/ur_hardware_interface', home)
    others = {cell_address('11311 4242', '/left/ur_hardware_interface', home),
              cell_address('11312 4242', '/ur_hardware_interface', home),
              cell_address('11311 4243', '/ur_hardware_interface', home)}
    assert one not in others and len(others) == 3
    assert one.startswith(os.path.join(home, 'ur3_ft_gripper_cell') + os.sep) and len(one.encode()) < 108
    os.makedirs(os.path.dirname(one), mode=0o755)
    os.chmod(os.path.dirname(one), 0o755)  # made earlier, open to others: the server closes it
    cell = type('NoCell', (), {})()
    server = CellServer(cell, one)
    try:
        assert stat.S_IMODE(os.stat(os.path.dirname(one)).st_mode) == 0o700
    finally:
        server.close()
    assert not os.path.exists(one)
