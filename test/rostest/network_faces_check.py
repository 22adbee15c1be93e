#!/usr/bin/env python3
"""rostest node: the controller's network faces and ur_robot_driver's ROS interface drive one robot
(network_faces.test): the Dashboard Server on 29999, with a client written from UR's Dashboard Server
document, and RTDE on 30004, with the client written from UR's RTDE guide (ur3_ft_gripper_testing); and the
2F-140 on the gripper URCap's socket (63352) beside its Robotiq topics, and on Modbus RTU (minimalmodbus on its
serial port) and Modbus TCP (a client written from Robotiq's manual, as its gateway is read); and the FT 300's
data stream on its serial line beside its topic."""
import os
import socket
import struct
import time
import unittest

import rospy
import rostest
from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input, Robotiq2FGripper_robot_output
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, String
from std_srvs.srv import Trigger
from ur_msgs.srv import SetIO
from ur_dashboard_msgs.msg import RobotMode
from ur_dashboard_msgs.srv import GetRobotMode

from ur3_ft_gripper_testing.rostest_helpers import TIMEOUT, Recorder, wait_for, wait_for_log
from ur3_ft_gripper_testing.rtde_client import RtdeClient

PORT = 29999
RTDE_PORT = 30004
REALTIME_PORT = 30003
URCAP_PORT = 63352  # Robotiq's gripper URCap, on the robot's address
NODE = '/ur_hardware_interface'
TARGET = [0.3, -1.4, 1.3, -1.5, -1.5, 0.4]


class Dashboard(object):
    def __init__(self, address):
        self.socket = socket.create_connection((address, PORT), timeout=TIMEOUT)
        self.lines = self.socket.makefile('rb')
        self.greeting = self.line()

    def line(self):
        return self.lines.readline().decode('ascii').rstrip('\n')

    def ask(self, command):
        self.socket.sendall((command + '\n').encode('ascii'))
        return self.line()

    def close(self):
        self.lines.close()
        self.socket.close()


class NetworkFacesTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('network_faces_check')
        cls.address = rospy.get_param('~robot_ip')
        cls.rosout = Recorder('/rosout', Log)
        cls.modes = Recorder(NODE + '/robot_mode', RobotMode)
        cls.joint_states = Recorder('joint_states', JointState)
        for name in ('dashboard/get_robot_mode', 'dashboard/power_on', 'dashboard/brake_release'):
            rospy.wait_for_service(NODE + '/' + name, TIMEOUT)
        cls.get_robot_mode = rospy.ServiceProxy(NODE + '/dashboard/get_robot_mode', GetRobotMode)
        # The node listens once it is up: the services above come first.
        cls.client = wait_for(lambda: cls.connect(), 'the Dashboard Server on %s:%d' % (cls.address, PORT))

    @classmethod
    def connect(cls):
        try:
            return Dashboard(cls.address)
        except OSError:
            return None

    def mode_on_ros(self):
        return self.get_robot_mode().robot_mode.mode

    def test_1_what_the_network_commands_the_ros_interface_reports(self):
        self.assertEqual(self.client.greeting, 'Connected: Universal Robots Dashboard Server')
        self.assertEqual(self.client.ask('robotmode'), 'Robotmode: RUNNING')
        self.assertEqual(self.client.ask('power off'), 'Powering off')
        self.assertEqual(self.mode_on_ros(), RobotMode.POWER_OFF)
        wait_for(lambda: any(m.mode == RobotMode.POWER_OFF for m in self.modes.since(0.0)),
                 'robot_mode POWER_OFF on ROS')

    def test_2_what_ros_commands_the_network_reports(self):
        self.client.ask('power off')
        self.assertTrue(rospy.ServiceProxy(NODE + '/dashboard/power_on', Trigger)().success)
        wait_for(lambda: self.client.ask('robotmode') == 'Robotmode: IDLE', 'IDLE over the network')
        self.assertTrue(rospy.ServiceProxy(NODE + '/dashboard/brake_release', Trigger)().success)
        wait_for(lambda: self.client.ask('robotmode') == 'Robotmode: RUNNING', 'RUNNING over the network')
        self.assertEqual(self.mode_on_ros(), RobotMode.RUNNING)

    def test_3_bad_input_is_one_log_line_and_the_robot_goes_on(self):
        since = time.monotonic()
        bad = Dashboard(self.address)
        bad.socket.sendall(b'robotmode \xff\n')
        self.assertEqual(bad.lines.read(), b'')
        bad.close()
        wait_for_log(self.rosout, NODE, Log.WARN, 'not ASCII text', since)
        self.assertEqual(len([m for (_, m) in self.rosout.items_since(since) if m.name == NODE]), 1)
        self.joint_states.next_after(time.monotonic())
        self.assertEqual(self.client.ask('safetymode'), 'Safetymode: NORMAL')

    def rtde(self):
        client = RtdeClient(RTDE_PORT, self.address, timeout=TIMEOUT)
        self.assertTrue(client.negotiate(2))
        return client

    def test_4_rtde_reads_where_a_program_sent_on_ros_moved_the_joints(self):
        self.client.ask('power on')
        self.client.ask('brake release')
        wait_for(lambda: self.mode_on_ros() == RobotMode.RUNNING, 'RUNNING')
        script = rospy.Publisher(NODE + '/script_command', String, queue_size=1, latch=True)
        script.publish(String(data='movej([%s], a=3, v=2)' % ', '.join(repr(v) for v in TARGET)))
        wait_for(lambda: self.joint_states.latest() is not None and
                 max(abs(a - b) for a, b in zip(self.joint_states.latest().position, TARGET)) < 1e-6,
                 'joint_states at the program\'s target')
        client = self.rtde()
        client.setup_outputs(['actual_q', 'actual_qd', 'runtime_state'], 500)
        self.assertTrue(client.start())
        data = client.data()
        client.close()
        for actual, target in zip(data['actual_q'], TARGET):
            self.assertAlmostEqual(actual, target, delta=1e-6)
        self.assertEqual(data['actual_qd'], [0.0] * 6)

    def test_5_rtde_sets_the_speed_slider_ros_publishes_and_reads_the_outputs_ros_set(self):
        self.assertEqual(self.client.ask('play'), 'Starting program')  # the scaling is the slider's while it plays
        client = self.rtde()
        slider = client.setup_inputs(['speed_slider_mask', 'speed_slider_fraction'])
        client.write(slider, {'speed_slider_mask': 1, 'speed_slider_fraction': 0.4})
        scaling = Recorder('speed_scaling_factor', Float64)
        wait_for(lambda: scaling.latest() is not None and abs(scaling.latest().data - 0.4) < 1e-9,
                 'speed_scaling_factor 0.4 on ROS')
        client.write(slider, {'speed_slider_mask': 1, 'speed_slider_fraction': 1.0})
        set_io = rospy.ServiceProxy(NODE + '/set_io', SetIO)
        self.assertTrue(set_io(fun=SetIO._request_class.FUN_SET_DIGITAL_OUT, pin=2, state=1.0).success)
        client.setup_outputs(['actual_digital_output_bits'], 125)
        self.assertTrue(client.start())
        self.assertEqual(client.data()['actual_digital_output_bits'] & 0b100, 0b100)
        client.close()

    def test_6_bad_rtde_input_is_one_log_line_and_the_robot_goes_on(self):
        since = time.monotonic()
        bad = socket.create_connection((self.address, RTDE_PORT), timeout=TIMEOUT)
        bad.sendall(b'\x00\x03X')
        self.assertEqual(bad.recv(10), b'')
        bad.close()
        wait_for_log(self.rosout, NODE, Log.WARN, 'unknown type', since)
        self.joint_states.next_after(time.monotonic())
        client = self.rtde()
        self.assertEqual(client.controller_version()[0], 5)
        client.close()

    def test_7_a_program_sent_on_the_real_time_interface_moves_what_ros_reports(self):
        self.client.ask('power on')
        self.client.ask('brake release')
        wait_for(lambda: self.mode_on_ros() == RobotMode.RUNNING, 'RUNNING')
        realtime = socket.create_connection((self.address, REALTIME_PORT), timeout=TIMEOUT)
        home = [0.0, -1.2, 1.0, -1.4, -1.5, 0.2]
        realtime.sendall(('def from_network():\n  movej([%s], a=3, v=2)\nend\n'
                          % ', '.join(repr(v) for v in home)).encode())
        wait_for(lambda: max(abs(a - b) for a, b in zip(self.joint_states.latest().position, home)) < 1e-6,
                 'joint_states at the target of the program sent on 30003')
        realtime.close()

    def test_8_the_gripper_urcap_socket_and_the_gripper_topics_are_one_gripper(self):
        # As Robotiq's gripper URCap serves the 2F-140 on a robot's address: SET answered b"ack", GET "<VAR> <n>".
        status = Recorder('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input)
        command = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output, queue_size=1)
        urcap = wait_for(lambda: self.connect_to(URCAP_PORT), 'the gripper URCap socket on %s:%d'
                         % (self.address, URCAP_PORT))

        def get(name):
            urcap.sendall(('GET %s\n' % name).encode('ascii'))
            reply_name, value = urcap.recv(1024).decode('ascii').split()
            self.assertEqual(reply_name, name)
            return int(value)

        urcap.sendall(b'SET ACT 1\n')
        self.assertEqual(urcap.recv(1024), b'ack')
        wait_for(lambda: status.latest() and status.latest().gSTA == 3, 'gSTA 3 on the topic after SET ACT 1')
        self.assertEqual(get('STA'), 3)
        urcap.sendall(b'SET POS 255 SPE 255 FOR 100 GTO 1\n')
        self.assertEqual(urcap.recv(1024), b'ack')
        wait_for(lambda: status.latest().gOBJ == 3 and status.latest().gPR == 255,
                 'the topic to show the close the socket asked for, ended')
        self.assertEqual(get('POS'), status.latest().gPO)
        # And what the topic commands, the socket reads.
        wait_for(lambda: command.get_num_connections() > 0, 'the gripper node to subscribe')
        command.publish(Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=40, rSP=200, rFR=50))
        wait_for(lambda: get('PRE') == 40 and get('OBJ') == 3, "GET PRE 40 and OBJ 3 after the topic's command")
        self.assertEqual((get('SPE'), get('FOR')), (200, 50))
        urcap.close()

    def test_9_the_gripper_on_modbus_rtu_and_tcp_and_its_topics_are_one_gripper(self):
        import minimalmodbus
        status = Recorder('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input)
        command = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output, queue_size=1)
        path = rospy.get_param('~gripper_serial_port')
        wait_for(lambda: os.path.exists(path), 'the 2F-140 serial port at %s' % path)
        # As Robotiq's Modbus RTU node opens its USB adapter: slave 9, 115200 8N1.
        rtu = minimalmodbus.Instrument(path, 9, mode=minimalmodbus.MODE_RTU)
        rtu.serial.baudrate, rtu.serial.timeout = 115200, TIMEOUT
        # Reset, then activate and close, written at 0x03E8 (rACT bit 0, rGTO bit 3; rPR, rSP, rFR).
        rtu.write_registers(0x03E8, [0x0000, 0x0000, 0x0000])
        wait_for(lambda: status.latest() and status.latest().gSTA == 0, 'gSTA 0 on the topic after the reset')
        rtu.write_registers(0x03E8, [0x0900, 0x00FF, 0xFF64])
        wait_for(lambda: status.latest().gSTA == 3 and status.latest().gOBJ == 3 and status.latest().gPR == 255,
                 'the topic to show the activation and close Modbus asked for, ended')
        registers = rtu.read_registers(0x07D0, 3, functioncode=3)  # as robotiq_modbus_rtu reads them
        data = struct.pack('>3H', *registers)
        self.assertEqual((data[0] & 1, (data[0] >> 4) & 3, data[3]), (1, 3, 255))
        wait_for(lambda: status.latest().gPO == struct.pack('>3H', *rtu.read_registers(0x07D0, 3))[4],
                 'the same gPO on the topic and on Modbus RTU')
        # What the topic commands, the gateway reads (function 4 from register 0, as robotiq_modbus_tcp does).
        wait_for(lambda: command.get_num_connections() > 0, 'the gripper node to subscribe')
        command.publish(Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=40, rSP=200, rFR=50))
        gateway = socket.create_connection((self.address, rospy.get_param('~gripper_gateway_port')), timeout=TIMEOUT)

        def gateway_status():
            gateway.sendall(struct.pack('>HHHBBHH', 7, 0, 6, 0, 4, 0, 3))
            header = gateway.recv(7)
            self.assertEqual(struct.unpack('>HHHB', header), (7, 0, 9, 0))
            return gateway.recv(8)[2:]

        wait_for(lambda: gateway_status()[3] == 40, 'gPR 40 on the gateway after the topic\'s command')
        gateway.close()
        rtu.serial.close()

    def test_10_the_ft300_stream_carries_the_readings_its_topic_publishes(self):
        import minimalmodbus
        from robotiq_ft_sensor.msg import ft_sensor
        path = rospy.get_param('~ft_serial_port')
        wait_for(lambda: os.path.exists(path), 'the FT 300 serial port at %s' % path)
        line = minimalmodbus.Instrument(path, 9, mode=minimalmodbus.MODE_RTU)
        line.serial.baudrate, line.serial.timeout = 19200, TIMEOUT
        firmware = struct.pack('>3H', *line.read_registers(500, 3))  # as rq_sensor probes it: 'F' first
        self.assertEqual(chr(firmware[0]), 'F')
        readings = Recorder('robotiq_ft_sensor', ft_sensor)
        wait_for(lambda: readings.latest() is not None, 'a reading on robotiq_ft_sensor')
        # rq_sensor's start of the stream, byte for byte, and the sensor's echo before the frames.
        line.serial.write(bytes.fromhex('09 10 01 9A 00 01 02 02 00 CD CA'))
        self.assertEqual(line.serial.read(8), bytes.fromhex('09 10 01 9A 00 01 21 52'))
        data = line.serial.read(16 * 100)  # a second of the stream
        line.serial.write(b'\xff' * 50)  # the stop
        frames = [struct.unpack('<6h', data[i + 2:i + 14]) for i in range(0, len(data), 16)]
        self.assertTrue(all(data[i:i + 2] == b'\x20\x4e' for i in range(0, len(data), 16)))
        # Frame for message, in order: the stream's counts are the topic's values (0.01 N, 0.001 N m).
        def published():
            return [(round(m.Fx * 100), round(m.Fy * 100), round(m.Fz * 100), round(m.Mx * 1000),
                     round(m.My * 1000), round(m.Mz * 1000)) for m in readings.since(0.0)]

        first = wait_for(lambda: frames[0] in published() and published().index(frames[0]) + 1,
                         "the stream's first frame on the topic") - 1
        wait_for(lambda: len(published()) >= first + len(frames), 'the topic to publish the streamed readings')
        self.assertEqual(published()[first:first + len(frames)], frames)
        line.serial.close()

    def connect_to(self, port):
        try:
            return socket.create_connection((self.address, port), timeout=TIMEOUT)
        except OSError:
            return None


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'network_faces', NetworkFacesTest)
