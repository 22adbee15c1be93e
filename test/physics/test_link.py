"""The link between the cell (the arm's process) and the FT 300 and 2F-140 nodes' processes."""
import json
import os
import stat
import subprocess
import sys

import pytest

from conftest import START, Served
from ur3_ft_gripper_description.devices.physics.link import CellClient, CellServer, LinkError

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
    stamp, wrench = out['wrench']
    assert stamp >= 0.0 and wrench[2] == pytest.approx(0.975 * 9.80665, rel=0.02)  # the 2F-140 hanging
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
    assert sorted(truth) == ['arm_position', 'contact_force', 'finger', 'gripper_base', 'objects']
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
