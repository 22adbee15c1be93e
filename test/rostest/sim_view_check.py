#!/usr/bin/env python3
"""rostest node: in view_ur3_ft_gripper.launch, the simulated devices reach TF and RViz's topics."""
import time
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import WrenchStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

from ur3_ft_gripper_description import kinematics

TIMEOUT = 20.0


class SimViewTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('sim_view_check')
        cls.prefix = rospy.get_param('~prefix', '')
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        cls.model = kinematics.Model(rospy.get_param('robot_description'))
        cls.command = rospy.Publisher('gripper/command', Float64, queue_size=1)
        end = time.monotonic() + TIMEOUT
        while cls.command.get_num_connections() == 0 and time.monotonic() < end:
            time.sleep(0.05)

    def pad_gap(self):
        """Distance between the two finger pads' frames, from TF."""
        left = self.buffer.lookup_transform(self.prefix + 'base_link', self.prefix + 'left_inner_finger_pad',
                                            rospy.Time(0), rospy.Duration(TIMEOUT))
        right = self.buffer.lookup_transform(self.prefix + 'base_link', self.prefix + 'right_inner_finger_pad',
                                             rospy.Time(0), rospy.Duration(TIMEOUT))
        a = kinematics.transform_msg_matrix(left.transform)[:3, 3]
        b = kinematics.transform_msg_matrix(right.transform)[:3, 3]
        return float(np.linalg.norm(a - b))

    def finger_angle(self):
        msg = rospy.wait_for_message('joint_states', JointState, TIMEOUT)
        return dict(zip(msg.name, msg.position))[self.prefix + 'finger_joint']

    def settle(self, command):
        self.command.publish(Float64(command))
        end = time.monotonic() + TIMEOUT
        while time.monotonic() < end:
            if abs(rospy.wait_for_message('gripper/opening', Float64, TIMEOUT).data - command) < 1e-9:
                time.sleep(0.5)  # joint_state_publisher and robot_state_publisher catch up
                return
        self.fail('gripper/opening never reached %g' % command)

    def test_wrench_is_in_the_prefixed_sensor_frame(self):
        msg = rospy.wait_for_message('robotiq_ft_wrench', WrenchStamped, TIMEOUT)
        self.assertEqual(msg.header.frame_id, self.prefix + 'robotiq_ft_frame_id')
        w = msg.wrench.force
        # The gripper's weight (0.975 kg) within a few noise deviations (0.1 N).
        self.assertAlmostEqual(np.linalg.norm([w.x, w.y, w.z]), 0.975 * 9.80665, delta=1.0)

    def test_gripper_command_moves_the_fingers_in_tf(self):
        self.settle(0.140)
        open_gap, open_angle = self.pad_gap(), self.finger_angle()
        self.settle(0.0)
        closed_gap, closed_angle = self.pad_gap(), self.finger_angle()
        self.assertAlmostEqual(open_angle, 0.0, places=6)
        upper = self.model.joints[self.prefix + 'finger_joint'].upper
        self.assertAlmostEqual(closed_angle, upper, places=6)
        self.assertGreater(open_gap - closed_gap, 0.1, 'the pads close by more than 10 cm')
        self.settle(0.140)
        self.assertAlmostEqual(self.pad_gap(), open_gap, places=6)


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'sim_view', SimViewTest)
