"""ur_rtde (PyPI ur-rtde, SDU's client of the UR controller) against the simulated arm's network faces.

The simulated cell runs as users start it, `roslaunch ur3_ft_gripper_description
ur_ft_gripper_bringup.launch sim:=true sim_robot_ip:=...`, on a loopback address
of its own and a ROS master of its own. ur_rtde's receive, IO and dashboard clients connect as they do to a
robot. What they read is checked against known truths: the start pose the
launch gave, the TCP pose pinocchio computes for those joints from the exported
model, the robot mode the dashboard asked for, the speed slider the IO client
set. Times are the controller's own (RTDE's timestamp), not the wall clock's,
except to wait for the node to come up.
"""
import math
import os
import random
import socket
import subprocess
import time

import numpy as np
import pinocchio
import pytest
import rtde_io
import rtde_receive
from dashboard_client import DashboardClient

from conftest import exported_urdf

# A CB3 (RTDE at 125 Hz) and an e-Series (500 Hz): ur_rtde sets itself up by the controller's version.
UR_TYPES = ['ur3', 'ur5e']
START = [0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0]  # the arm's documented start pose
COME_UP = 120.0  # wall s for roslaunch, a master and the node on a busy machine
# The RTDE guide's robot modes and robot status bits.
POWER_OFF, RUNNING = 3, 7
POWER_ON_BIT = 1


def free_port():
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        return probe.getsockname()[1]


@pytest.fixture(scope='module', params=UR_TYPES)
def ur_type(request):
    return request.param


@pytest.fixture(scope='module')
def robot_ip(ur_type):
    """The address of a simulated cell of `ur_type` started for these tests (a loopback address of its own)."""
    address = '127.0.%d.%d' % (random.randint(1, 254), random.randint(2, 254))
    master = free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % master)
    node = subprocess.Popen(['roslaunch', '-p', str(master), 'ur3_ft_gripper_description',
                             'ur_ft_gripper_bringup.launch', 'ur_type:=' + ur_type, 'sim:=true',
                             'sim_robot_ip:=' + address],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
    try:
        deadline = time.monotonic() + COME_UP
        while True:
            try:
                socket.create_connection((address, 30004), timeout=1.0).close()
                break
            except OSError:
                assert node.poll() is None, 'sim_arm.launch ended: %s' % node.stdout.read()
                assert time.monotonic() < deadline, 'the simulated arm did not listen within %g s' % COME_UP
                time.sleep(0.2)
        yield address
    finally:
        node.terminate()
        node.wait(timeout=60)


def controller_wait(receive, condition, seconds):
    """Poll `condition()` until it holds, for at most `seconds` of the controller's own time."""
    end = receive.getTimestamp() + seconds
    while not condition():
        assert receive.getTimestamp() < end, 'not within %g s of the controller\'s time' % seconds
        time.sleep(0.01)


@pytest.fixture(scope='module')
def receive(robot_ip):
    client = rtde_receive.RTDEReceiveInterface(robot_ip)
    yield client
    client.disconnect()


def test_the_receive_interface_reads_the_start_pose_and_the_robot_running(receive):
    assert receive.isConnected()
    assert receive.getActualQ() == pytest.approx(START, abs=1e-9)
    assert receive.getActualQd() == pytest.approx([0.0] * 6, abs=1e-12)
    assert receive.getRobotMode() == RUNNING and receive.getSafetyMode() == 1  # NORMAL
    first = receive.getTimestamp()
    controller_wait(receive, lambda: receive.getTimestamp() >= first + 0.5, 5.0)


def test_the_tcp_pose_is_the_one_pinocchio_computes_from_the_exported_model(ur_type, receive):
    model = pinocchio.buildModelFromUrdf(exported_urdf('--ur-type', ur_type), mimic=True)
    data = model.createData()
    q = pinocchio.neutral(model)
    for name, value in zip(('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint',
                            'wrist_2_joint', 'wrist_3_joint'), receive.getActualQ()):
        q[model.joints[model.getJointId(name)].idx_q] = value
    pinocchio.framesForwardKinematics(model, data, q)
    # The controller's base frame is ur_description's `base`; its TCP is tool0 until set_tcp.
    base = data.oMf[model.getFrameId('base')]
    tool0 = base.actInv(data.oMf[model.getFrameId('tool0')])
    pose = receive.getActualTCPPose()
    assert pose[:3] == pytest.approx(list(tool0.translation), abs=1e-6)
    angle_axis = pinocchio.log3(tool0.rotation)
    assert np.allclose(pose[3:], angle_axis, atol=1e-6) or \
        math.isclose(np.linalg.norm(angle_axis), math.pi, abs_tol=1e-6)


def test_the_dashboard_powers_off_and_rtde_reads_the_mode(robot_ip, receive):
    dashboard = DashboardClient(robot_ip)
    dashboard.connect()
    try:
        assert receive.getRobotMode() == RUNNING
        dashboard.powerOff()
        controller_wait(receive, lambda: receive.getRobotMode() == POWER_OFF, 5.0)
        assert not receive.getRobotStatus() & POWER_ON_BIT
        dashboard.brakeRelease()
        controller_wait(receive, lambda: receive.getRobotMode() == RUNNING, 10.0)
        assert receive.getRobotStatus() & POWER_ON_BIT
    finally:
        dashboard.disconnect()


def test_the_io_interface_sets_the_speed_slider_and_a_digital_output(robot_ip, receive):
    io = rtde_io.RTDEIOInterface(robot_ip)
    try:
        assert io.setSpeedSlider(0.3)
        controller_wait(receive, lambda: receive.getTargetSpeedFraction() == pytest.approx(0.3), 5.0)
        assert io.setStandardDigitalOut(3, True)
        controller_wait(receive, lambda: receive.getDigitalOutState(3), 5.0)
        assert receive.getActualDigitalOutputBits() == 1 << 3
    finally:
        io.disconnect()
