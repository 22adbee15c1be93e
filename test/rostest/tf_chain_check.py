#!/usr/bin/env python3
"""rostest node: the TF tree published from robot_description runs tool0 -> sensor -> gripper -> pads.

robot_description comes from the load launch as users run it, which expands
the model through the xacro module of the `xacro` package that launch files
name (ros-noetic-xacro; on Debian 12, PyPI's xacro: see tools/debian12).
"""
import os
import subprocess
import unittest

import numpy as np
import rospkg
import rospy
import rostest
import tf2_ros
from roslaunch.substitution_args import resolve_args

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.model import description
from ur3_ft_gripper_testing import rostest_helpers

CHAIN = ['base_link', 'tool0', 'ft300_mounting_plate', 'ft300_sensor', 'robotiq_ft_frame_id',
         'robotiq_arg2f_base_link']
PADS = ['left_inner_finger_pad', 'right_inner_finger_pad']

FT300_ALONE = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'data', 'ft300_alone.xacro')


class TfChainTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('tf_chain_check')
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)

    def lookup(self, target, source):
        """Pose of `source` in `target` as a 4x4 matrix, from TF."""
        return rostest_helpers.lookup(self.buffer, target, source)

    def test_the_load_launch_set_the_model(self):
        self.assertIn('<robot name="ur3_ft_gripper"', rospy.get_param('robot_description'))

    def test_the_xacro_that_launch_files_name_expands_upstreams_own_model(self):
        # $(find xacro)/xacro, as ur_description's load_ur.launch runs it.
        xacro = resolve_args('$(find xacro)/xacro')
        ur3 = os.path.join(rospkg.RosPack().get_path('ur_description'), 'urdf', 'ur3.xacro')
        run = subprocess.run([xacro, ur3], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             universal_newlines=True, timeout=60)
        self.assertEqual(run.returncode, 0, run.stderr)
        model = kinematics.Model(run.stdout)
        self.assertEqual(model.chain('base_link', 'tool0')[-1].child, 'tool0')

    def test_chain_from_base_link_through_sensor_to_gripper(self):
        for parent, child in zip(CHAIN, CHAIN[1:]):
            self.lookup(parent, child)  # raises if the two frames are not connected

    def test_both_finger_pads_are_below_the_gripper_base(self):
        for pad in PADS:
            pose = self.lookup('robotiq_arg2f_base_link', pad)
            self.assertGreater(pose[2, 3], 0.1, pad + ' should be well out along the approach axis')

    def test_finger_pads_are_mirror_images(self):
        left = self.lookup('robotiq_arg2f_base_link', PADS[0])[:3, 3]
        right = self.lookup('robotiq_arg2f_base_link', PADS[1])[:3, 3]
        np.testing.assert_allclose(left[1], -right[1], atol=1e-6)
        np.testing.assert_allclose(left[2], right[2], atol=1e-6)
        self.assertGreater(abs(left[1] - right[1]), 0.1, 'at finger_joint 0 the gripper is open')

    def test_tool0_to_gripper_equals_upstream_ft300_macro(self):
        ft300 = kinematics.Model(description.to_xml(description.run_xacro(FT300_ALONE)))
        expected = ft300.transform('tool0', 'robotiq_ft_frame_id')
        np.testing.assert_allclose(self.lookup('tool0', 'robotiq_arg2f_base_link'), expected, atol=1e-6)

    def test_tf_matches_the_robot_description_it_was_built_from(self):
        model = kinematics.Model(rospy.get_param('robot_description'))
        for frame in CHAIN[1:] + PADS:
            np.testing.assert_allclose(self.lookup('base_link', frame),
                                       model.transform('base_link', frame), atol=1e-6, err_msg=frame)


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'tf_chain', TfChainTest)
