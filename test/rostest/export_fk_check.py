#!/usr/bin/env python3
"""rostest node: TF from robot_state_publisher equals an independent library's FK of export_urdf's file.

The launch file loads robot_description for one configuration (~ur_type,
~ft_sensor, ~gripper, ~world, ~prefix) and runs robot_state_publisher; this
node exports the same configuration with export_urdf's module, loads the file
with yourdfpy (not our own kinematics code), publishes random joint values on
/joint_states and compares every link's pose in TF with yourdfpy's.
"""
import os
import tempfile
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
import yourdfpy
from sensor_msgs.msg import JointState

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.model import export
from ur3_ft_gripper_testing import rostest_helpers

TIMEOUT = rospy.Duration(20)
TRIALS = 3
TOLERANCE = 1e-6  # m (and the rotation matrices' entries)


def param(name, default):
    return str(rospy.get_param('~' + name, default)).lower()


class ExportFkTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('export_fk_check')
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        cls.publisher = rospy.Publisher('joint_states', JointState, queue_size=10)
        cls.mappings = export.model_mappings(
            ur_type=param('ur_type', 'ur3'), prefix=rospy.get_param('~prefix', ''),
            ft_sensor=param('ft_sensor', 'true') == 'true', gripper=param('gripper', 'true') == 'true',
            world=param('world', 'false') == 'true')
        cls.folder = tempfile.mkdtemp(prefix='export_fk_')
        cls.files = {}
        for mode, absolute in (('package', False), ('absolute', True)):
            path = os.path.join(cls.folder, '%s.urdf' % mode)
            with open(path, 'w') as f:
                f.write(export.export_urdf(cls.mappings, absolute=absolute))
            cls.files[mode] = path
        cls.urdf = yourdfpy.URDF.load(cls.files['absolute'], load_meshes=False,
                                      build_collision_scene_graph=False, load_collision_meshes=False)

    def test_exported_model_is_the_loaded_robot_description(self):
        loaded = kinematics.Model(rospy.get_param('robot_description'))
        self.assertEqual(sorted(loaded.links), sorted(self.urdf.link_map))
        self.assertEqual(loaded.root(), self.urdf.base_link)

    def test_every_mesh_path_resolves_in_both_modes(self):
        for mode, path in self.files.items():
            urdf = yourdfpy.URDF.load(path, load_meshes=False, build_scene_graph=False)
            uris = [g.geometry.mesh.filename for link in urdf.robot.links
                    for g in list(link.visuals) + list(link.collisions) if g.geometry.mesh is not None]
            self.assertGreaterEqual(len(uris), 14)
            for uri in uris:
                self.assertTrue(uri.startswith('/' if mode == 'absolute' else 'package://'), uri)
                self.assertTrue(os.path.isfile(export.resolve_uri(uri)), uri)

    def publish_until_in_tf(self, cfg, moving_link):
        """Publish joint values until robot_state_publisher has put them in TF; their stamp.

        robot_state_publisher skips joint states that come within its publish
        interval of the last ones it used, so a skipped message is sent again
        with a new stamp once TF has shown, within a wait, that it did not arrive.
        """
        deadline = rospy.Time.now() + TIMEOUT
        while True:
            msg = JointState(name=list(cfg), position=[cfg[n] for n in cfg])
            msg.header.stamp = rospy.Time.now()
            self.publisher.publish(msg)
            if self.buffer.can_transform(self.urdf.base_link, moving_link, msg.header.stamp,
                                         rospy.Duration(0.5)):
                return msg.header.stamp
            self.assertLess(rospy.Time.now(), deadline, 'robot_state_publisher never used the joint states')

    def test_tf_equals_independent_forward_kinematics_for_random_joint_values(self):
        rostest_helpers.wait_for_subscribers(self.publisher)
        rng = np.random.default_rng(1234)
        root = self.urdf.base_link
        moving = self.urdf.actuated_joint_names
        self.assertGreaterEqual(len(moving), 6)
        for trial in range(TRIALS):
            cfg = {}
            for name in moving:
                limit = self.urdf.joint_map[name].limit
                cfg[name] = float(rng.uniform(max(limit.lower, -np.pi), min(limit.upper, np.pi)))
            stamp = self.publish_until_in_tf(cfg, self.urdf.joint_map[moving[-1]].child)
            self.urdf.update_cfg(cfg)
            for link in self.urdf.link_map:
                if link == root:
                    continue
                tf = self.buffer.lookup_transform(root, link, stamp, TIMEOUT)
                np.testing.assert_allclose(
                    rostest_helpers.transform_matrix(tf.transform),
                    self.urdf.get_transform(link, root), atol=TOLERANCE,
                    err_msg='%s, trial %d, joints %s' % (link, trial, cfg))


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'export_fk', ExportFkTest)
