#!/usr/bin/env python3
"""rostest node: the real-cell bring-up with sim:=true, run for real (bringup_sim.test)."""
import unittest

import numpy as np
import rosgraph
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import WrenchStamped
from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input, Robotiq2FGripper_robot_output
from sensor_msgs.msg import JointState

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices import gripper_joint_states, gripper_model
from ur3_ft_gripper_testing import rostest_helpers
from ur3_ft_gripper_testing.rostest_helpers import TIMEOUT, wait_for
ARM_JOINTS = ('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
              'wrist_3_joint')
# TF against the model: the finger angle table is exact to 1e-6 rad, which
# moves a pad by far less than 1e-5 m; the register is one count = 0.6 mm.
GAP_TOLERANCE = 1e-5


class BringupSimTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('bringup_sim_check')
        cls.prefix = rospy.get_param('~prefix', '')
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        description = rospy.get_param('robot_description')
        cls.model = kinematics.Model(description)
        cls.fingers = gripper_model.GripperKinematics(description, prefix=cls.prefix)

        # The register scale gripper_joint_states uses (its parameters, else its defaults).
        def node_param(name, default=None):
            return rospy.get_param(name.replace('~', '/gripper_joint_states/', 1), default)
        cls.scale = gripper_joint_states.scale_from_params(node_param)

        cls.command = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output,
                                      queue_size=1, latch=True)
        wait_for(lambda: cls.command.get_num_connections(), 'robotiq2FGripper subscribes')

    def status(self):
        return rospy.wait_for_message('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input, TIMEOUT)

    def send(self, **registers):
        self.command.publish(Robotiq2FGripper_robot_output(**registers))

    def pad_gap(self):
        return rostest_helpers.pad_gap(self.buffer, self.fingers, prefix=self.prefix)

    def expected_gap(self, gpo):
        """The model's pad gap for a status gPO: the register's opening, within what the model can show."""
        opening = self.scale.opening(gpo)
        return min(max(opening, self.fingers.min_opening), self.fingers.max_opening)

    def move_to(self, position):
        """Command rPR = position; return the settled gPO once the gripper reports the motion done."""
        self.send(rACT=1, rGTO=1, rPR=position, rSP=255, rFR=150)
        done = wait_for(lambda: (lambda s: s if s.gPR == position and s.gOBJ == 3 else None)(self.status()),
                          'gripper reports rPR %d reached' % position)
        expected = self.expected_gap(done.gPO)
        wait_for(lambda: abs(self.pad_gap() - expected) <= GAP_TOLERANCE,
                   'TF pad gap reaches %.6f m for gPO %d' % (expected, done.gPO))
        return done.gPO, self.pad_gap()

    def test_fingers_follow_register_commands_in_tf(self):
        self.send()  # reset, then activate as Robotiq's controllers do
        wait_for(lambda: self.status().gSTA == 0, 'reset')
        self.send(rACT=1, rGTO=1, rSP=255, rFR=150)
        wait_for(lambda: self.status().gSTA == 3, 'activation completes')
        _, open_gap = self.move_to(0)
        closed_gpo, closed_gap = self.move_to(255)
        half_gpo, half_gap = self.move_to(128)
        self.assertAlmostEqual(open_gap, self.fingers.max_opening, delta=GAP_TOLERANCE)
        self.assertAlmostEqual(closed_gap, self.expected_gap(closed_gpo), delta=GAP_TOLERANCE)
        self.assertGreater(open_gap - closed_gap, 0.1, 'the pads close by more than 10 cm')
        self.assertTrue(closed_gap < half_gap < open_gap, (closed_gap, half_gap, open_gap))

    def test_two_publishers_on_joint_states_each_with_its_own_joints(self):
        # The mechanism the launch file relies on: robot_state_publisher listens
        # on joint_states, where the arm's and the gripper's publishers meet.
        state = rosgraph.Master(rospy.get_name()).getSystemState()
        publishers = dict((topic, set(nodes)) for topic, nodes in state[0])
        subscribers = dict((topic, set(nodes)) for topic, nodes in state[1])
        self.assertEqual(publishers.get('/joint_states'), {'/ur_hardware_interface', '/gripper_joint_states'})
        self.assertIn('/robot_state_publisher', subscribers.get('/joint_states', set()))
        arm = set(self.prefix + j for j in ARM_JOINTS)
        finger = {self.prefix + 'finger_joint'}
        seen = []

        def both_seen():
            names = set(rospy.wait_for_message('joint_states', JointState, TIMEOUT).name)
            seen.append(names)
            return arm in seen and finger in seen
        wait_for(both_seen, 'arm and finger messages on joint_states')
        for names in seen:
            self.assertIn(names, (arm, finger), 'a message mixes or misses joints: %s' % sorted(names))

    def test_arm_from_the_simulated_driver_in_tf(self):
        arm = set(self.prefix + j for j in ARM_JOINTS)
        state = wait_for(lambda: (lambda m: m if set(m.name) == arm else None)(
            rospy.wait_for_message('joint_states', JointState, TIMEOUT)), 'an arm message on joint_states')
        msg = self.buffer.lookup_transform(self.prefix + 'base_link', self.prefix + 'tool0', rospy.Time(0),
                                           rospy.Duration(TIMEOUT))
        expected = self.model.transform(self.prefix + 'base_link', self.prefix + 'tool0',
                                        dict(zip(state.name, state.position)))
        np.testing.assert_allclose(rostest_helpers.transform_matrix(msg.transform), expected, atol=1e-6)

    def test_simulated_sensor_under_the_real_name(self):
        msg = rospy.wait_for_message('robotiq_ft_wrench', WrenchStamped, TIMEOUT)
        self.assertEqual(msg.header.frame_id, self.prefix + 'robotiq_ft_frame_id')
        publishers = dict((topic, set(nodes)) for topic, nodes in
                          rosgraph.Master(rospy.get_name()).getSystemState()[0])
        self.assertEqual(publishers.get('/robotiq_ft_wrench'), {'/robotiq_ft_sensor'})


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'bringup_sim', BringupSimTest)
