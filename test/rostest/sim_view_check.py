#!/usr/bin/env python3
"""rostest node: in view_ur3_ft_gripper.launch, the simulated devices reach TF and RViz's topics."""
import os
import signal
import time
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import WrenchStamped
from sensor_msgs.msg import JointState
from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input, Robotiq2FGripper_robot_output

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices import gripper_model, sim_params, wrench_model
from ur3_ft_gripper_testing import rostest_helpers
from ur3_ft_gripper_testing.rostest_helpers import TIMEOUT


class SimViewTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('sim_view_check')
        cls.prefix = rospy.get_param('~prefix', '')
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        cls.model = kinematics.Model(rospy.get_param('robot_description'))
        cls.fingers = gripper_model.GripperKinematics(rospy.get_param('robot_description'),
                                                      prefix=cls.prefix)
        cls.command = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output,
                                      queue_size=1)
        rostest_helpers.wait_for_subscribers(cls.command)

    def pad_gap(self):
        return rostest_helpers.pad_gap(self.buffer, self.fingers, prefix=self.prefix)

    def finger_angle(self):
        msg = rospy.wait_for_message('joint_states', JointState, TIMEOUT)
        return dict(zip(msg.name, msg.position))[self.prefix + 'finger_joint']

    def status(self):
        return rospy.wait_for_message('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input, TIMEOUT)

    def settle(self, rpr, gpo):
        """Send rPR; wait for gPO and for TF to show the angle gripper_joint_states gives for it."""
        self.command.publish(Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=rpr, rSP=255, rFR=150))
        rostest_helpers.wait_for(lambda: (lambda s: s.gSTA == 3 and s.gPO == gpo and s.gOBJ == 3)(self.status()),
                                 'gPO %d' % gpo, step=0)
        target = rospy.wait_for_message('gripper/joint_states', JointState, TIMEOUT).position[0]
        rostest_helpers.wait_for(lambda: abs(self.finger_angle() - target) < 1e-9,
                                 'finger_joint %g in joint_states' % target, step=0)
        # TF reaches this node after joint_states (robot_state_publisher turns one into the other): wait
        # for the pads to stand where the model puts them for that angle, on a busy machine too.
        rostest_helpers.wait_for(lambda: abs(self.pad_gap() - self.fingers.opening(target)) < 1e-5,
                                 'the pads in TF at finger_joint %g' % target, step=0.01)

    def test_wrench_is_in_the_prefixed_sensor_frame(self):
        msg = rospy.wait_for_message('robotiq_ft_wrench', WrenchStamped, TIMEOUT)
        self.assertEqual(msg.header.frame_id, self.prefix + 'robotiq_ft_frame_id')
        w = msg.wrench.force
        # The gripper's weight (0.975 kg) within a few noise deviations (0.1 N).
        self.assertAlmostEqual(np.linalg.norm([w.x, w.y, w.z]), 0.975 * 9.80665, delta=1.0)

    def test_a_late_sensor_node_loses_no_reading(self):
        """The FT 300 streams from its own clock; a node held up serves the readings late, each with its own
        stamp, as rq_sensor reads a real unit's samples from the serial line's buffer."""
        period_ns = round(1e9 / wrench_model.load_sensor_spec(sim_params.default_devices_file()).rate)
        recorder = rostest_helpers.Recorder('robotiq_ft_wrench', WrenchStamped)
        recorder.next_after(0.0)
        node = rostest_helpers.node_pid('robotiq_ft_sensor')
        os.kill(node, signal.SIGSTOP)
        try:
            time.sleep(0.3)  # the wall clock: it is the node that is held, not the cell's time
        finally:
            os.kill(node, signal.SIGCONT)
        resumed = rospy.Time.now()
        recorder.stamped_after(resumed + rospy.Duration(0.5))
        stamps = np.array([m.header.stamp.to_nsec() for m in recorder.since(0.0)])
        self.assertGreater(stamps[-1] - stamps[0], 0.8e9)
        self.assertEqual(sorted(set(np.diff(stamps))), [period_ns])

    def test_register_command_moves_the_fingers_in_tf(self):
        self.settle(0, 3)  # activates as well (rACT 1 from reset)
        open_gap, open_angle = self.pad_gap(), self.finger_angle()
        self.settle(255, 230)
        closed_gap = self.pad_gap()
        self.assertAlmostEqual(open_angle, 0.0, places=6)
        self.assertAlmostEqual(open_gap, self.fingers.max_opening, places=5)
        self.assertAlmostEqual(closed_gap, 0.0, delta=1e-5)  # the pads touch
        self.settle(0, 3)
        self.assertAlmostEqual(self.pad_gap(), open_gap, places=6)


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'sim_view', SimViewTest)
