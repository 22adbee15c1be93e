#!/usr/bin/env python3
"""rostest node: the Dashboard Server on 29999 and ur_robot_driver's ROS interface drive one robot
(network_dashboard.test). The client is written from UR's Dashboard Server document."""
import socket
import time
import unittest

import rospy
import rostest
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from ur_dashboard_msgs.msg import RobotMode
from ur_dashboard_msgs.srv import GetRobotMode

from ur3_ft_gripper_testing.rostest_helpers import TIMEOUT, Recorder, wait_for, wait_for_log

PORT = 29999
NODE = '/ur_hardware_interface'


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


class NetworkDashboardTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('network_dashboard_check')
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


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'network_dashboard', NetworkDashboardTest)
