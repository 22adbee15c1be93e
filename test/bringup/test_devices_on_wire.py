"""The simulated devices on the wire, as a user puts them there and hands them to the real drivers.

The view launch with devices_on_wire:=true starts the FT 300 and the 2F-140 on their serial lines at the
documented paths, and each node logs the value the real bring-up's argument takes. Here a real roslaunch
(on a master of its own) starts them; minimalmodbus reads each device where its line says; and roslaunch's
own loader shows that the real bring-up given those values hands them to rq_sensor (~serial_id) and to
Robotiq's Modbus RTU node (its device argument), as it would on the robot.
"""
import os
import re
import subprocess
import time

import minimalmodbus
import pytest

from test_bringup_launch import REAL_ARGS, load_nodes
from ur3_ft_gripper_testing.rostest_helpers import free_port, stop_group

COME_UP = 120.0  # wall s for roslaunch, a master and the nodes on a busy machine
FT_LINE = re.compile(r"the FT 300 answers on its serial line at (\S+) \((\S+)\): for rq_sensor, the real "
                     r"bring-up's ft_serial_id:=(\S+)")
GRIPPER_LINE = re.compile(r"the 2F-140 answers Modbus RTU \(slave 9, 115200 8N1\) on (\S+) \((\S+)\): for Robotiq's "
                          r"Modbus RTU node, the real bring-up's gripper_device:=(\S+)")


@pytest.fixture(scope='module')
def on_wire(tmp_path_factory):
    """The paths and values the nodes logged: {'ft': (link, pty, ft_serial_id), 'gripper': (...)}."""
    log = tmp_path_factory.mktemp('on_wire') / 'roslaunch.log'
    port = free_port()
    # Python buffers a node's output in blocks when it goes to a file, not a terminal: unbuffered, each
    # line reaches the log as the user's terminal shows it.
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % port, PYTHONUNBUFFERED='1')
    with open(str(log), 'w') as output:
        launch = subprocess.Popen(['roslaunch', '-p', str(port), 'ur3_ft_gripper_description',
                                   'view_ur3_ft_gripper.launch', 'gui:=false', 'rviz:=false', 'devices_on_wire:=true'],
                                  env=env, stdout=output, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + COME_UP
        while True:
            text = log.read_text(errors='replace')
            ft, gripper = FT_LINE.search(text), GRIPPER_LINE.search(text)
            if ft and gripper:
                break
            assert launch.poll() is None, 'roslaunch ended:\n' + text[-3000:]
            assert time.monotonic() < deadline, 'the devices did not say where they are:\n' + text[-3000:]
            time.sleep(0.2)
        yield {'ft': ft.groups(), 'gripper': gripper.groups()}
    finally:
        stop_group(launch)


def test_the_lines_are_at_the_documented_paths_and_name_what_the_real_drivers_take(on_wire):
    link, pty, serial_id = on_wire['ft']
    assert link == '/tmp/ttyRobotiqFT300' and os.path.realpath(link) == pty and '/dev/' + serial_id == pty
    link, pty, device = on_wire['gripper']
    assert link == '/tmp/ttyRobotiq2F' and os.path.realpath(link) == pty and device == link


def test_each_device_answers_where_its_line_says(on_wire):
    sensor = minimalmodbus.Instrument('/dev/' + on_wire['ft'][2], 9, mode=minimalmodbus.MODE_RTU)
    sensor.serial.baudrate, sensor.serial.timeout = 19200, 5.0
    assert chr(sensor.read_register(500) >> 8) == 'F'  # rq_sensor's probe: the firmware's first letter
    # Its accelerometer (registers 190 to 192, thousandths of g), held still: gravity's reaction, 1 g.
    deadline, acceleration = time.monotonic() + COME_UP, [0, 0, 0]
    while not any(acceleration):  # zero until the node has the sensor's pose from TF
        assert time.monotonic() < deadline, 'the accelerometer read nothing'
        acceleration = [r - 0x10000 if r & 0x8000 else r for r in sensor.read_registers(190, 3)]
        time.sleep(0.1)
    assert sum(a * a for a in acceleration) ** 0.5 == pytest.approx(1000, abs=3), acceleration
    sensor.serial.close()
    gripper = minimalmodbus.Instrument(on_wire['gripper'][2], 9, mode=minimalmodbus.MODE_RTU)
    gripper.serial.baudrate, gripper.serial.timeout = 115200, 5.0
    status = gripper.read_registers(0x07D0, 3, functioncode=3)  # as Robotiq's node reads the status
    assert (status[0] >> 8) & 1 == 0  # gACT 0: in reset, as after a power-up
    gripper.serial.close()


def test_the_real_bringup_hands_those_values_to_the_real_drivers(on_wire):
    serial_id, device = on_wire['ft'][2], on_wire['gripper'][2]
    args = [a for a in REAL_ARGS if not a.startswith('ft_serial_id:=')]
    nodes, params = load_nodes('ur3_ft_gripper_bringup.launch', *(args + ['ft_serial_id:=' + serial_id,
                                                                          'gripper_device:=' + device]))
    assert params['/robotiq_ft_sensor/serial_id'] == serial_id
    assert (nodes['/robotiq2FGripper'].package, nodes['/robotiq2FGripper'].type) == (
        'robotiq_2f_gripper_control', 'Robotiq2FGripperRtuNode.py')
    assert nodes['/robotiq2FGripper'].args == device
