"""ur_rtde (PyPI ur-rtde, SDU's client of the UR controller) against the simulated arm's network faces.

The simulated cell runs as users start it, `roslaunch ur3_ft_gripper_description
ur_ft_gripper_bringup.launch sim:=true sim_robot_ip:=...`, on a loopback address
of its own and a ROS master of its own. ur_rtde's receive, IO, dashboard and control clients connect as they
do to a robot; the control client sends the robot its own URScript program (ur_rtde's control script) over
the primary interface and commands it through RTDE's registers. What they read is checked against known
truths: the start pose the launch gave, the TCP pose pinocchio computes for those joints from the exported
model, the robot mode the dashboard asked for, the speed slider the IO client set, the joints a movej was
given and the least time its profile allows, a straight line for movel, the speeds speedj and speedl asked
for, the last target of a servoj stream, a watchdog's period, and on physics the force a forceMode press
applies as the robot's own wrench and the FT 300 (rq_sensor's topic on the cell's master) read it, and the
block ur_rtde's moves and the gripper URCap's socket pick up, held at its width; and pymodbus (PyPI) on the
2F-140's serial line and gateway, as Robotiq's Modbus nodes drive it, closing on that block, and on the FT 300's
serial line, reading the identity rq_sensor prints and the readings its topic publishes. Times
are the controller's own (RTDE's timestamp), not the wall clock's, except to wait for the node to come up.
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
import yaml
import rtde_control
import rtde_io
import rtde_receive
from dashboard_client import DashboardClient
from pymodbus.client import ModbusSerialClient, ModbusTcpClient

from conftest import exported_urdf

# A CB3 (RTDE at 125 Hz) and an e-Series (500 Hz): ur_rtde sets itself up by the controller's version.
UR_TYPES = ['ur3', 'ur5e']
START = [0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0]  # the arm's documented start pose
COME_UP = 120.0  # wall s for roslaunch, a master and the node on a busy machine
# The RTDE guide's robot modes and robot status bits.
POWER_OFF, RUNNING = 3, 7
POWER_ON_BIT = 1
PLAYING = 2  # the RTDE guide's runtime_state
WATCHDOG_PERIOD = 1.0  # s: 1 / the watchdog's least frequency


def free_port():
    """A port for a master of one's own, as ur3_ft_gripper_testing's free_port picks it (this folder runs
    without the workspace): below the kernel's ephemeral ports, which every starting node takes from."""
    for _ in range(1000):
        port = random.randrange(15000, 29000)
        with socket.socket() as probe:
            try:
                probe.bind(('', port))
            except OSError:
                continue
            return port
    raise AssertionError('no free TCP port in 15000..28999')


@pytest.fixture(scope='module', params=UR_TYPES)
def ur_type(request):
    return request.param


# Each cell's output (roslaunch and its nodes), by address: a file, so that a full pipe never blocks a node.
CELL_LOGS = {}
# Each cell's ROS master, by address: the FT 300 is read on its ROS face, as rq_sensor serves it.
CELL_MASTERS = {}


def cell_log(address, lines=30):
    """The last `lines` of what the cell at `address` printed, for an assertion's message."""
    with open(CELL_LOGS[address], errors='replace') as log:
        return 'the cell printed, last:\n' + ''.join(log.readlines()[-lines:])


def bring_up(ur_type, log_dir, *arguments, sim_gateway=False):
    """The address of a simulated cell of `ur_type` started for these tests (a loopback address of its own, a
    master of its own), with the bring-up's `arguments` (and sim_gateway: the 2F-140's Modbus TCP gateway on
    that address); the bring-up ends with the generator."""
    address = '127.0.%d.%d' % (random.randint(1, 254), random.randint(2, 254))
    if sim_gateway:
        arguments += ('sim_gripper_gateway_ip:=' + address,)
    master = free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % master)
    CELL_LOGS[address] = str(log_dir / ('cell-%s.log' % address))
    CELL_MASTERS[address] = env['ROS_MASTER_URI']
    with open(CELL_LOGS[address], 'w') as output:
        node = subprocess.Popen(['roslaunch', '-p', str(master), 'ur3_ft_gripper_description',
                                 'ur_ft_gripper_bringup.launch', 'ur_type:=' + ur_type, 'sim:=true',
                                 'sim_robot_ip:=' + address] + list(arguments),
                                env=env, stdout=output, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + COME_UP
        while True:
            try:
                socket.create_connection((address, 30004), timeout=1.0).close()
                break
            except OSError:
                assert node.poll() is None, 'the bring-up ended: %s' % cell_log(address)
                assert time.monotonic() < deadline, 'the simulated arm did not listen within %g s' % COME_UP
                time.sleep(0.2)
        yield address
    finally:
        node.terminate()
        node.wait(timeout=60)


@pytest.fixture(scope='module')
def robot_ip(ur_type, tmp_path_factory):
    """A kinematic cell."""
    yield from bring_up(ur_type, tmp_path_factory.mktemp('kinematic'))


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


@pytest.fixture(scope='module')
def control(robot_ip, receive):
    """ur_rtde's RTDEControlInterface, its control script running on the simulated robot (at full speed: the
    IO test above leaves the speed slider lower)."""
    io = rtde_io.RTDEIOInterface(robot_ip)
    try:
        assert io.setSpeedSlider(1.0)
        controller_wait(receive, lambda: receive.getTargetSpeedFraction() == pytest.approx(1.0), 5.0)
    finally:
        io.disconnect()
    client = rtde_control.RTDEControlInterface(robot_ip)
    yield client
    client.stopScript()
    client.disconnect()


def test_the_control_script_runs_and_movej_reaches_the_joints_no_sooner_than_its_profile(control, receive):
    assert control.isProgramRunning()
    target = list(START)
    target[0] += 0.2
    start = receive.getTimestamp()
    assert control.moveJ(target, 1.0, 1.0)
    # The receive client's connection may be a package or two behind the control client's, which saw it end.
    controller_wait(receive, lambda: receive.getActualQ() == pytest.approx(target, abs=1e-6), 0.1)
    # 0.2 rad at a = v = 1: the speed never reaches v, a triangle of 2 sqrt(0.2 / a) s. Later, not sooner,
    # by the command's round trip through RTDE and the script.
    assert receive.getTimestamp() - start >= 2 * math.sqrt(0.2) - 0.01


def test_movel_keeps_the_tcp_on_a_straight_line(control, receive):
    start = receive.getActualTCPPose()
    target = list(start)
    target[2] += 0.05
    assert control.moveL(target, 0.25, 0.5, True)  # asynchronous: the path is sampled while it runs
    samples = []
    end = receive.getTimestamp() + 10.0
    while control.getAsyncOperationProgress() >= 0 or not samples:
        samples.append(receive.getActualTCPPose())
        assert receive.getTimestamp() < end, 'movel did not end within 10 s of the controller\'s time'
        time.sleep(0.002)
    controller_wait(receive, lambda: receive.getActualTCPPose()[2] == pytest.approx(target[2], abs=1e-6), 2.0)
    assert receive.getActualTCPPose() == pytest.approx(target, abs=1e-6)
    assert len(samples) > 10
    for pose in samples:
        assert pose[:2] == pytest.approx(start[:2], abs=1e-6)  # on the vertical line through the start
        assert start[2] - 1e-6 <= pose[2] <= target[2] + 1e-6
        assert pose[3:] == pytest.approx(start[3:], abs=1e-6)  # the tool does not turn


def test_inverse_kinematics_gives_the_joints_the_arm_has(control, receive):
    assert control.getInverseKinematics(receive.getActualTCPPose()) == pytest.approx(receive.getActualQ(), abs=1e-6)
    assert control.isJointsWithinSafetyLimits(receive.getActualQ())
    assert not control.isJointsWithinSafetyLimits([7.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # beyond +-2 pi
    assert not control.isPoseWithinSafetyLimits([3.0, 0.0, 0.0, 0.0, math.pi, 0.0])  # 3 m away: out of reach


def test_speedj_reaches_the_speed_asked_and_speedstop_stops(control, receive):
    assert control.speedJ([0.2, 0.0, 0.0, 0.0, 0.0, 0.0], 1.0, 0.0)
    controller_wait(receive, lambda: receive.getActualQd()[0] == pytest.approx(0.2, abs=1e-9), 2.0)
    assert receive.getActualQd()[1:] == pytest.approx([0.0] * 5, abs=1e-9)
    assert control.speedStop(2.0)
    controller_wait(receive, lambda: receive.getActualQd() == pytest.approx([0.0] * 6, abs=1e-9), 2.0)



def test_speedl_moves_the_tool_at_the_speed_asked_and_speedstop_stops(control, receive):
    assert control.speedL([0.0, 0.0, 0.02, 0.0, 0.0, 0.0], 0.5, 0.0)  # 2 cm/s up, the tool not turning
    # Within 0.1 mm/s: RTDE's TCP speed is the joints' speeds over a cycle through the Jacobian at its end.
    controller_wait(receive, lambda: receive.getActualTCPSpeed()[2] == pytest.approx(0.02, abs=1e-4), 2.0)
    assert receive.getActualTCPSpeed() == pytest.approx([0.0, 0.0, 0.02, 0.0, 0.0, 0.0], abs=1e-4)
    assert control.speedStop(2.0)
    controller_wait(receive, lambda: receive.getActualTCPSpeed() == pytest.approx([0.0] * 6, abs=1e-9), 2.0)


def test_servoj_streamed_at_500_hz_is_followed_to_its_last_target(control, receive):
    q = receive.getActualQ()
    for _ in range(250):  # half a second of the client's clock, a target every 2 ms (0.2 rad/s on the wrist)
        period = control.initPeriod()
        q[5] += 0.0004
        assert control.servoJ(q, 0.5, 0.5, 0.002, 0.1, 300)
        control.waitPeriod(period)
    # The servo holds the last target until servoStop: the wrist gets there.
    controller_wait(receive, lambda: receive.getActualQ() == pytest.approx(q, abs=1e-4), 2.0)
    assert control.servoStop(10.0)


def test_stopscript_ends_the_program_and_reuploadscript_runs_it_again(control, receive):
    control.stopScript()
    controller_wait(receive, lambda: receive.getRuntimeState() != PLAYING, 2.0)
    assert control.reuploadScript()
    # Each client reads a stream of its own: the control client's view, which it commands by, may come a few
    # packages after the receive client's on a busy machine.
    controller_wait(receive, lambda: receive.getRuntimeState() == PLAYING and control.isProgramRunning(), 5.0)
    assert control.setTcp([0.0] * 6)  # the script sent again takes commands (the flange, as the cell started)

def test_the_watchdog_stops_the_program_one_period_after_the_last_kick(control, receive):
    # The program stops one period of the controller's time after a silence. Kicked every 20 ms: a period
    # of 1 s leaves a busy machine most of a second to deliver a kick late (0.1 s, 80 ms, was not enough).
    assert control.setWatchdog(1.0 / WATCHDOG_PERIOD)
    for _ in range(20):
        assert control.kickWatchdog()
        time.sleep(0.02)
    assert control.isProgramRunning()
    assert control.kickWatchdog()
    silent_from = receive.getTimestamp()  # at the last kick or before it: RTDE's data lags its inputs
    # Read on the receive client's own connection, the stop and its time come in one package.
    controller_wait(receive, lambda: receive.getRuntimeState() != PLAYING, WATCHDOG_PERIOD + 5.0)
    assert receive.getTimestamp() - silent_from >= WATCHDOG_PERIOD - 0.01



# -- on physics -------------------------------------------------------------------------------------------

# Where the gripper's TCP starts, in base_link (m): over the default world's free table (its top at z = 0),
# where examples/force_mode_press.py presses. The controller's base is base_link turned half a turn about z.
PRESS_XY, PRESS_HEIGHT = (0.2986, 0.1123), 0.06
PRESS_FORCES = (10.0, 20.0, 40.0)  # N, one after the other in one press
# s of the controller's time: from the air to the first force read (the approach and the press), from one
# force's reading to the next's, and reading.
SETTLE, RESETTLE, MEASURE = 2.5, 1.0, 1.0
FT300_RATE = 100.0  # Hz: rq_sensor's stream
# N: the spread (standard deviation) of the robot's own force reading over a window of a steady press
# (measured: under 0.03 N). A press ringing about the right mean spread 13 N at 40 N on the UR3.
STEADY = 0.1


# The 2F-140's serial port and its gateway's port, of each physics cell by address (the gateway on the cell's
# address, on a port a user may take).
GRIPPER_LINES = {}
GATEWAY_PORT = 5020
# The FT 300's serial line of each physics cell, by address.
SENSOR_LINES = {}


@pytest.fixture(scope='module')
def physics_ip(ur_type, tmp_path_factory):
    """A physics cell, on its simulated clock at real time (ur_rtde keeps the wall clock's time), its 2F-140 also
    on Modbus RTU (a serial port path) and Modbus TCP (a gateway on the cell's address)."""
    log_dir = tmp_path_factory.mktemp('physics')
    line, sensor_line = str(log_dir / 'ttyRobotiq2F'), str(log_dir / 'ttyRobotiqFT300')
    for address in bring_up(ur_type, log_dir, 'physics:=true', 'sim_gripper_serial_port:=' + line,
                            'sim_gripper_gateway_port:=%d' % GATEWAY_PORT, 'sim_ft_serial_port:=' + sensor_line,
                            sim_gateway=True):
        GRIPPER_LINES[address], SENSOR_LINES[address] = line, sensor_line
        yield address


def gripper_tcp(ur_type):
    """The gripper's TCP in tool0 (x, y, z, rotation vector), from the exported model by pinocchio."""
    model = pinocchio.buildModelFromUrdf(exported_urdf('--ur-type', ur_type), mimic=True)
    data = model.createData()
    pinocchio.framesForwardKinematics(model, data, pinocchio.neutral(model))
    offset = data.oMf[model.getFrameId('tool0')].actInv(data.oMf[model.getFrameId('gripper_tcp')])
    return list(offset.translation) + list(pinocchio.log3(offset.rotation))


def ros_tool(address, *command, **popen):
    """A ROS command-line tool (rosservice, rostopic) against the cell at `address`'s master."""
    env = dict(os.environ, ROS_MASTER_URI=CELL_MASTERS[address], PYTHONUNBUFFERED='1')
    return subprocess.Popen(list(command), env=env, universal_newlines=True, **popen)


def zero_ft300(address):
    """rq_sensor's SET_ZERO (command_id 8) on robotiq_ft_sensor_acc, as users call it."""
    call = ros_tool(address, 'rosservice', 'call', '/robotiq_ft_sensor_acc', '8', '', stdout=subprocess.PIPE,
                    stderr=subprocess.STDOUT)
    output = call.communicate(timeout=COME_UP)[0]
    assert call.returncode == 0 and 'success: True' in output, output


class FT300Recording(object):
    """robotiq_ft_wrench as `rostopic echo -p` prints it (stamp and force), from start() until stop(until=)."""

    def __init__(self, address, path):
        self.address, self.path = address, str(path)

    def start(self):
        """Once rostopic prints readings: it takes a while to come up, longer on a busy machine."""
        self.output = open(self.path, 'w')
        self.process = ros_tool(self.address, 'rostopic', 'echo', '-p', '/robotiq_ft_wrench', stdout=self.output,
                                stderr=subprocess.STDOUT)
        deadline = time.monotonic() + COME_UP
        while not self.readings():
            assert self.process.poll() is None and time.monotonic() < deadline, \
                'rostopic echo printed no reading of robotiq_ft_wrench: %s' % open(self.path).read()[-2000:]
            time.sleep(0.1)

    def readings(self):
        """[(stamp s, fx, fy, fz)] printed so far."""
        with open(self.path) as lines:
            rows = [line.split(',') for line in lines if line[:1].isdigit()]
        return [(int(row[2]) * 1e-9, float(row[4]), float(row[5]), float(row[6])) for row in rows if len(row) > 9]

    def stop(self, until):
        """The readings up to simulated time `until`, once rostopic has printed them (it trails the cell)."""
        deadline = time.monotonic() + COME_UP
        while not any(stamp >= until for stamp, *_ in self.readings()):
            assert self.process.poll() is None and time.monotonic() < deadline, \
                'robotiq_ft_wrench did not reach %.3f s: %s' % (until, open(self.path).read()[-2000:])
            time.sleep(0.1)
        self.process.terminate()
        self.process.wait(timeout=30)
        self.output.close()
        return self.readings()


def test_force_mode_presses_on_the_table_with_the_force_asked(ur_type, physics_ip, tmp_path):
    receive = rtde_receive.RTDEReceiveInterface(physics_ip)
    control = rtde_control.RTDEControlInterface(physics_ip)
    try:
        assert control.setTcp(gripper_tcp(ur_type)), cell_log(physics_ip)
        # The gripper pointing down (its TCP's z along the base's -z) over the table.
        above = [-PRESS_XY[0], -PRESS_XY[1], PRESS_HEIGHT, 0.0, math.pi, 0.0]
        assert control.moveJ_IK(above, 1.0, 1.0)
        # Both sensors zeroed in the air, as a user zeroes them before a press.
        assert control.zeroFtSensor()
        zero_ft300(physics_ip)
        ft300 = FT300Recording(physics_ip, tmp_path / 'ft300.csv')
        ft300.start()
        frame = receive.getActualTCPPose()
        # One press, the force stepped up without lifting: each force read over its own window.
        windows, robot = [], []
        window_start = receive.getTimestamp() + SETTLE
        for force in PRESS_FORCES:
            window = (window_start, window_start + MEASURE)
            readings = []
            while receive.getTimestamp() < window[1]:
                period = control.initPeriod()
                # The tool's z, down: the force the robot applies to the table, at most 5 cm/s along it.
                assert control.forceMode(frame, [0, 0, 1, 0, 0, 0], [0.0, 0.0, force, 0.0, 0.0, 0.0], 2,
                                         [0.1, 0.1, 0.05, 0.17, 0.17, 0.17])
                if receive.getTimestamp() >= window[0]:
                    readings.append(receive.getActualTCPForce())
                control.waitPeriod(period)
            windows.append(window)
            robot.append(readings)
            window_start = window[1] + RESETTLE
        assert control.forceModeStop()
        # The FT 300's stamps are the cell's simulated time, which RTDE's timestamp counts too.
        recorded = ft300.stop(until=windows[-1][1])
        seen = []
        for force, window, readings in zip(PRESS_FORCES, windows, robot):
            sensed = [r[1:] for r in recorded if window[0] <= r[0] <= window[1]]
            mean, sensed_mean = np.mean(readings, axis=0), np.mean(sensed, axis=0)
            seen.append('%g N: robot wrench %s (z spread %.2f), FT 300 force %s (%d readings)' % (
                force, np.round(mean, 2), np.std(readings, axis=0)[2], np.round(sensed_mean, 2), len(sensed)))
            # The table pushes the tool up with the force the robot applies down. The FT 300, zeroed in the
            # air, reads the table's push along its z (the tool's), against it: -force.
            assert mean[2] == pytest.approx(force, abs=max(0.05 * force, 0.5)), seen
            assert np.std(readings, axis=0)[2] < STEADY, seen
            assert len(sensed) >= 0.9 * MEASURE * FT300_RATE, seen
            assert sensed_mean[2] == pytest.approx(-force, abs=max(0.05 * force, 0.5)), seen
        assert control.moveJ_IK(above, 1.0, 1.0)
    finally:
        control.stopScript()
        control.disconnect()
        receive.disconnect()


# -- ur_rtde with the gripper URCap's socket, on physics ---------------------------------------------------

# The default world's block (config/worlds/default.yaml): 50 mm square, 120 mm tall, standing at (0.30, -0.15)
# in base_link. Grasped 40 mm below its top, as examples/pick_and_weigh.py grasps.
BLOCK_XY, BLOCK_WIDTH, BLOCK_TOP, GRASP_DEPTH = (0.30, -0.15), 0.05, 0.12, 0.04
URCAP_PORT = 63352
# MuJoCo's soft contacts: each pad sinks a little into the held object under the grip
# (ur3_ft_gripper_testing.grasp, which this folder does not import).
GAP_TOLERANCE = 0.001


class UrcapGripper(object):
    """The 2F-140 on Robotiq's gripper URCap socket, as ur_rtde's robotiq_gripper example speaks to it."""

    def __init__(self, address):
        self.socket = socket.create_connection((address, URCAP_PORT), timeout=10.0)

    def set(self, **values):
        self.socket.sendall(('SET' + ''.join(' %s %d' % item for item in values.items()) + '\n').encode('ascii'))
        assert self.socket.recv(1024) == b'ack'

    def get(self, name):
        self.socket.sendall(('GET %s\n' % name).encode('ascii'))
        reply_name, value = self.socket.recv(1024).decode('ascii').split()
        assert reply_name == name
        return int(value)

    def close(self):
        self.socket.close()


def register_position(opening):
    """gPO of a pad opening (m), by the unit's register scale in config/sim_devices.yaml."""
    with open(os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'sim_devices.yaml')) as stream:
        unit = yaml.safe_load(stream)['gripper']
    counts_per_metre = (unit['gpo_closed'] - unit['gpo_open']) / unit['stroke']
    return unit['gpo_closed'] - opening * counts_per_metre, counts_per_metre


def gripper_request(rACT=0, rGTO=0, rATR=0, rPR=0, rSP=0, rFR=0):
    """The three request registers, as Robotiq's manual lays them out (action request, two reserved bytes,
    position, speed, force; high byte first)."""
    return [(rACT | rGTO << 3 | rATR << 4) << 8, rPR, rSP << 8 | rFR]


def gripper_status(registers):
    """gSTA, gOBJ, gFLT, gPR, gPO of the status registers, as the manual lays them out."""
    status, fault, echo, position = registers[0] >> 8, registers[1] >> 8, registers[1] & 0xFF, registers[2] >> 8
    return dict(gSTA=(status >> 4) & 3, gOBJ=(status >> 6) & 3, gFLT=fault & 0x0F, gPR=echo, gPO=position)


class ModbusGripper(object):
    """The 2F-140 through pymodbus (PyPI), as Robotiq's ROS nodes talk to it: on its serial line (slave 9,
    115200 8N1, requests at 0x03E8 with function 16, status at 0x07D0 with function 3) or through the gateway
    (registers from 0, status with function 4)."""

    def __init__(self, client, request, status, read, device_id):
        self.client, self.request_at, self.status_at, self.device_id = client, request, status, device_id
        self.read_status = getattr(client, read)
        assert client.connect(), 'pymodbus could not open %s' % client

    def command(self, **registers):
        reply = self.client.write_registers(self.request_at, gripper_request(**registers), device_id=self.device_id)
        assert not reply.isError(), reply

    def status(self):
        reply = self.read_status(self.status_at, count=3, device_id=self.device_id)
        assert not reply.isError(), reply
        return gripper_status(reply.registers)

    def close(self):
        self.client.close()


def test_pymodbus_on_the_gripper_line_and_gateway_closes_on_the_block_opens_and_reads_a_fault(ur_type, physics_ip):
    receive = rtde_receive.RTDEReceiveInterface(physics_ip)
    control = rtde_control.RTDEControlInterface(physics_ip)
    line = ModbusGripper(ModbusSerialClient(GRIPPER_LINES[physics_ip], baudrate=115200, bytesize=8, parity='N',
                                            stopbits=1, timeout=5.0), 0x03E8, 0x07D0, 'read_holding_registers', 9)
    gateway = ModbusGripper(ModbusTcpClient(physics_ip, port=GATEWAY_PORT, timeout=5.0), 0, 0,
                            'read_input_registers', 0)
    try:
        # A move before activation is a fault (manual: gFLT 0x07, the activation bit must be set first).
        line.command(rACT=0)
        line.command(rACT=0, rGTO=1, rPR=255, rSP=255, rFR=100)
        controller_wait(receive, lambda: line.status()['gFLT'] == 0x07, 2.0)
        assert gateway.status()['gFLT'] == 0x07  # one gripper behind both
        line.command(rACT=1, rGTO=1, rPR=0, rSP=255, rFR=100)
        controller_wait(receive, lambda: line.status()['gSTA'] == 3 and line.status()['gOBJ'] == 3, 5.0)
        assert control.setTcp(gripper_tcp(ur_type)), cell_log(physics_ip)
        x, y = -BLOCK_XY[0], -BLOCK_XY[1]  # the controller's base is base_link turned half a turn about z
        above = [x, y, BLOCK_TOP + 0.08, 0.0, math.pi, 0.0]
        around = [x, y, BLOCK_TOP - GRASP_DEPTH, 0.0, math.pi, 0.0]
        assert control.moveJ_IK(above, 1.0, 1.0)
        assert control.moveL(around, 0.1, 0.5)
        gateway.command(rACT=1, rGTO=1, rPR=255, rSP=255, rFR=100)  # close, through the gateway
        controller_wait(receive, lambda: gateway.status()['gOBJ'] != 0, 5.0)
        held_at, counts_per_metre = register_position(BLOCK_WIDTH)
        held = line.status()
        assert held['gOBJ'] == 2, 'the close did not stop on the block: %s' % held
        assert abs(held['gPO'] - held_at) <= GAP_TOLERANCE * counts_per_metre + 0.5, held
        line.command(rACT=1, rGTO=1, rPR=0, rSP=255, rFR=100)  # open, on the line: the block stays standing
        controller_wait(receive, lambda: line.status()['gOBJ'] == 3, 5.0)
        assert gateway.status()['gPR'] == 0
        assert control.moveL(above, 0.1, 0.5)
    finally:
        line.close()
        gateway.close()
        control.stopScript()
        control.disconnect()
        receive.disconnect()


def test_pymodbus_reads_the_ft300_identity_as_rq_sensor_prints_it_and_the_force_its_topic_publishes(physics_ip,
                                                                                                    tmp_path):
    client = ModbusSerialClient(SENSOR_LINES[physics_ip], baudrate=19200, bytesize=8, parity='N', stopbits=1,
                                timeout=5.0)
    assert client.connect()
    recording = FT300Recording(physics_ip, tmp_path / 'ft300.csv')
    try:
        def registers(address, count):
            reply = client.read_holding_registers(address, count=count, device_id=9)
            assert not reply.isError(), reply
            return reply.registers
        firmware = registers(500, 3)
        data = b''.join(r.to_bytes(2, 'big') for r in firmware)
        assert chr(data[0]) == 'F'  # rq_sensor takes a sensor whose firmware does not start with F for none
        assert '%c%c%c-%d.%d.%d' % tuple(data) == 'FTS-0.0.0'  # config/sim_devices.yaml
        assert registers(514, 1) == [2026]
        # The force registers (counts of 0.01 N, signed) hold the device's own reading: each read is one of
        # robotiq_ft_wrench's messages, exactly (the readings carry the sensor's noise: each its own), plus
        # the zero the driver took, the same for every read (rq_sensor zeroes in the driver, not the device;
        # the cell's force test zeroed it).
        recording.start()
        read = [tuple(r - 0x10000 if r & 0x8000 else r for r in registers(180, 3))]
        for _ in range(4):
            time.sleep(0.05)
            read.append(tuple(r - 0x10000 if r & 0x8000 else r for r in registers(180, 3)))
        time.sleep(1.0)  # wall s: rostopic prints what came meanwhile
        published = {tuple(round(100 * f) for f in row[1:]) for row in recording.readings()}
        zeros = None
        for force in read:
            found = {tuple(r - p for r, p in zip(force, topic)) for topic in published}
            zeros = found if zeros is None else zeros & found
        assert zeros and len(set(read)) > 1, (read, len(published))  # and the registers follow the readings
        # The accelerometer (190 to 192, thousandths of g: Robotiq's FT-150/300 manual), MuJoCo's at the
        # sensor: the arm holds still, so it reads gravity's reaction, 1 g.
        acceleration = [r - 0x10000 if r & 0x8000 else r for r in registers(190, 3)]
        assert sum(a * a for a in acceleration) ** 0.5 == pytest.approx(1000, abs=10), acceleration
    finally:
        if getattr(recording, 'process', None) is not None:
            recording.process.terminate()
            recording.output.close()
        client.close()


def test_ur_rtde_and_the_gripper_urcap_socket_pick_up_the_block(ur_type, physics_ip):
    receive = rtde_receive.RTDEReceiveInterface(physics_ip)
    control = rtde_control.RTDEControlInterface(physics_ip)
    gripper = UrcapGripper(physics_ip)
    try:
        # Activation as the example does it: reset, then ACT 1 until STA 3.
        gripper.set(ACT=0, ATR=0)
        gripper.set(ACT=1)
        controller_wait(receive, lambda: gripper.get('STA') == 3, 5.0)
        gripper.set(POS=0, SPE=255, FOR=100, GTO=1)
        controller_wait(receive, lambda: gripper.get('OBJ') == 3, 5.0)  # open, at rest
        assert control.setTcp(gripper_tcp(ur_type)), cell_log(physics_ip)
        # The controller's base is base_link turned half a turn about z.
        x, y = -BLOCK_XY[0], -BLOCK_XY[1]
        above = [x, y, BLOCK_TOP + 0.08, 0.0, math.pi, 0.0]
        assert control.moveJ_IK(above, 1.0, 1.0)
        assert control.moveL([x, y, BLOCK_TOP - GRASP_DEPTH, 0.0, math.pi, 0.0], 0.1, 0.5)
        gripper.set(POS=255, SPE=255, FOR=100, GTO=1)
        controller_wait(receive, lambda: gripper.get('OBJ') != 0, 5.0)
        held_at, counts_per_metre = register_position(BLOCK_WIDTH)
        assert gripper.get('OBJ') == 2, 'the close did not stop on the block'  # stopped on an object, closing
        assert abs(gripper.get('POS') - held_at) <= GAP_TOLERANCE * counts_per_metre + 0.5, gripper.get('POS')
        assert control.moveL(above, 0.1, 0.5)
        assert gripper.get('OBJ') == 2, 'the block slipped out while lifting'
    finally:
        gripper.close()
        control.stopScript()
        control.disconnect()
        receive.disconnect()
