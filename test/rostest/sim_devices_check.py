#!/usr/bin/env python3
"""rostest node: ft300_sim and gripper_sim against the real model, TF and master (sim_devices.test)."""
import math
import threading
import time
import unittest

import numpy as np
import roslaunch
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import WrenchStamped
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from std_srvs.srv import Trigger

from ur3_ft_gripper_description import kinematics

G = 9.80665
GRIPPER_MASS, GRIPPER_COM = 0.975, np.array([0.0, 0.0, 0.062])  # config/sim_devices.yaml
OBJECT_MASS, OBJECT_COM = 0.5, np.array([0.0, 0.0, 0.2])        # sim_devices.test
ARM = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint',
       'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint']
# Sensor z axis straight down (checked against the model in the test).
TOOL_DOWN = [0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0]
ZERO = [0.0] * 6  # the gripper points along base_link +y: horizontal
SENSOR = 'robotiq_ft_frame_id'
TIMEOUT = 20.0


def expected_wrench(rotation, mass, com):
    """Weight of `mass` at `com` (sensor frame) on a sensor with orientation `rotation` in a z-up frame."""
    force = mass * G * rotation.T.dot([0.0, 0.0, -1.0])
    return force, np.cross(com, force)


def wrench_arrays(msg):
    w = msg.wrench
    return (np.array([w.force.x, w.force.y, w.force.z]),
            np.array([w.torque.x, w.torque.y, w.torque.z]))


class Recorder(object):
    """Messages of one topic with their receipt time."""

    def __init__(self, topic, msg_type):
        self.items = []
        self.lock = threading.Lock()
        rospy.Subscriber(topic, msg_type, self._add, queue_size=1000)

    def _add(self, msg):
        with self.lock:
            self.items.append((time.monotonic(), msg))

    def since(self, t):
        with self.lock:
            return [m for (r, m) in self.items if r >= t]

    def next_after(self, t, timeout=TIMEOUT):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            got = self.since(t)
            if got:
                return got[0]
            time.sleep(0.01)
        raise AssertionError('nothing received within %g s' % timeout)


class SimDevicesTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('sim_devices_check')
        cls.model = kinematics.Model(rospy.get_param('robot_description'))
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        cls.arm = list(TOOL_DOWN)
        cls.publishing = threading.Event()
        cls.publishing.set()
        cls.joint_publisher = rospy.Publisher('joint_states', JointState, queue_size=10)
        cls.wrench = Recorder('robotiq_ft_wrench', WrenchStamped)
        cls.loaded = Recorder('loaded/robotiq_ft_wrench', WrenchStamped)
        cls.zeroing = Recorder('zeroing/robotiq_ft_wrench', WrenchStamped)
        cls.no_tf = Recorder('no_tf/robotiq_ft_wrench', WrenchStamped)
        cls.rosout = Recorder('/rosout', Log)  # straight from the nodes: no rosout node needed
        cls.gripper_joints = Recorder('gripper/joint_states', JointState)
        cls.opening = Recorder('gripper/opening', Float64)
        cls.command = rospy.Publisher('gripper/command', Float64, queue_size=10)
        threading.Thread(target=cls._publish_joints, daemon=True).start()
        end = time.monotonic() + TIMEOUT  # a command sent before gripper_sim listens is lost
        while cls.command.get_num_connections() == 0 and time.monotonic() < end:
            time.sleep(0.05)

    @classmethod
    def _publish_joints(cls):
        rate = rospy.Rate(50)
        while not rospy.is_shutdown():
            if cls.publishing.is_set():
                msg = JointState(name=ARM + ['finger_joint'], position=list(cls.arm) + [0.0])
                msg.header.stamp = rospy.Time.now()  # TF stamps follow it: the age ft300_sim checks
                try:
                    cls.joint_publisher.publish(msg)
                except rospy.ROSException:
                    return  # shutting down
            try:
                rate.sleep()
            except rospy.ROSInterruptException:
                return

    # -- helpers -------------------------------------------------------------

    def lookup(self, target, source):
        msg = self.buffer.lookup_transform(target, source, rospy.Time(0), rospy.Duration(TIMEOUT))
        return kinematics.transform_msg_matrix(msg.transform)

    def move_to(self, arm):
        """Publish `arm`, wait until TF shows it; returns the sensor's orientation in base_link."""
        type(self).arm = list(arm)
        expected = self.model.transform('base_link', SENSOR, dict(zip(ARM, arm)))
        end = time.monotonic() + TIMEOUT
        while time.monotonic() < end:
            try:
                if np.allclose(self.lookup('base_link', SENSOR), expected, atol=1e-6):
                    return expected[:3, :3]
            except tf2_ros.TransformException:
                pass
            time.sleep(0.02)
        self.fail('TF never showed the commanded arm pose')

    def reading(self, recorder):
        """The first wrench computed after now (one sensor period of margin)."""
        return wrench_arrays(recorder.next_after(time.monotonic() + 0.05))

    def warnings_from(self, node, text):
        return [m.msg for m in self.rosout.since(0) if m.name == node and m.level == Log.WARN
                and text in m.msg]

    def wait_opening(self, value, timeout=TIMEOUT):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if abs(self.opening.next_after(time.monotonic()).data - value) < 1e-9:
                return
        self.fail('the gripper never reached %g' % value)

    # -- ft300_sim -------------------------------------------------------------

    def test_tool_pointing_down_reads_the_gripper_weight_along_plus_z(self):
        rotation = self.move_to(TOOL_DOWN)
        self.assertAlmostEqual(rotation[2, 2], -1.0, places=6, msg='TOOL_DOWN must point the sensor down')
        force, torque = self.reading(self.wrench)
        np.testing.assert_allclose(force, [0.0, 0.0, GRIPPER_MASS * G], atol=1e-4)
        np.testing.assert_allclose(torque, [0.0, 0.0, 0.0], atol=1e-4)

    def test_wrench_follows_the_pose_in_tf(self):
        rng = np.random.default_rng(7)
        for arm in [ZERO] + [list(rng.uniform(-math.pi, math.pi, 6)) for _ in range(4)]:
            rotation = self.move_to(arm)
            force, torque = self.reading(self.wrench)
            expected_force, expected_torque = expected_wrench(rotation, GRIPPER_MASS, GRIPPER_COM)
            np.testing.assert_allclose(force, expected_force, atol=1e-4, err_msg=str(arm))
            np.testing.assert_allclose(torque, expected_torque, atol=1e-4, err_msg=str(arm))

    def test_held_object_adds_its_weight_and_lever(self):
        self.move_to(TOOL_DOWN)
        force, _ = self.reading(self.loaded)
        self.assertAlmostEqual(force[2], (GRIPPER_MASS + OBJECT_MASS) * G, places=3)
        self.move_to(ZERO)  # horizontal: the weight acts on the combined lever arm
        _, torque = self.reading(self.loaded)
        lever = GRIPPER_MASS * GRIPPER_COM[2] + OBJECT_MASS * OBJECT_COM[2]
        self.assertAlmostEqual(np.linalg.norm(torque), lever * G, places=3)

    def test_zero_service_makes_later_readings_relative(self):
        zero = rospy.ServiceProxy('zeroing/robotiq_ft_zero', Trigger)
        zero.wait_for_service(TIMEOUT)
        first = self.move_to(ZERO)
        self.reading(self.zeroing)  # a reading at this pose exists before zeroing
        self.assertTrue(zero().success)
        force, torque = self.reading(self.zeroing)
        np.testing.assert_allclose(np.concatenate([force, torque]), 0.0, atol=1e-4)
        second = self.move_to(TOOL_DOWN)
        force, torque = self.reading(self.zeroing)
        f1, t1 = expected_wrench(first, GRIPPER_MASS, GRIPPER_COM)
        f2, t2 = expected_wrench(second, GRIPPER_MASS, GRIPPER_COM)
        np.testing.assert_allclose(force, f2 - f1, atol=1e-4)
        np.testing.assert_allclose(torque, t2 - t1, atol=1e-4)

    def test_unknown_sensor_frame_waits_warns_once_and_publishes_nothing(self):
        # Started from here, after the /rosout subscription, so that no warning can be missed.
        rospy.set_param('no_tf/ft300_sim/frame_id', 'no_such_sensor_frame')
        launch = roslaunch.scriptapi.ROSLaunch()
        launch.start()
        try:
            process = launch.launch(roslaunch.core.Node(
                'ur3_ft_gripper_description', 'ft300_sim', name='ft300_sim', namespace='/no_tf/'))
            zero = rospy.ServiceProxy('no_tf/robotiq_ft_zero', Trigger)
            zero.wait_for_service(TIMEOUT)
            time.sleep(4.0)
            self.assertTrue(process.is_alive())
            self.assertFalse(zero().success)  # serving, but nothing to zero
            self.assertEqual(self.no_tf.since(0), [])
            warnings = self.warnings_from('/no_tf/ft300_sim', 'waiting for TF')
            self.assertEqual(len(warnings), 1, warnings)
            self.assertIn('no_such_sensor_frame', warnings[0])
        finally:
            launch.stop()

    def test_stale_pose_stops_the_wrench_until_tf_updates(self):
        self.move_to(ZERO)
        self.publishing.clear()
        try:
            time.sleep(1.5)  # ~max_pose_age (0.5 s) plus margin
            quiet_since = time.monotonic()
            time.sleep(1.0)
            self.assertEqual(self.wrench.since(quiet_since), [], 'published for a stale pose')
        finally:
            self.publishing.set()
        self.wrench.next_after(time.monotonic())  # resumes
        warnings = self.warnings_from('/ft300_sim', 's old')
        self.assertEqual(len(warnings), 1, [(m.level, m.msg) for m in self.rosout.since(0) if m.name == '/ft300_sim'])

    # -- gripper_sim -------------------------------------------------------------

    def test_gripper_closes_at_its_speed_to_the_joint_limit(self):
        self.command.publish(Float64(0.140))
        self.wait_opening(0.140)
        t0 = time.monotonic()
        self.command.publish(Float64(0.0))
        self.wait_opening(0.0)
        moving = [(r, m.data) for (r, m) in self.opening.items if r >= t0 and 0.01 < m.data < 0.13]
        self.assertGreater(len(moving), 10)
        slope = np.polyfit([r for r, _ in moving], [d for _, d in moving], 1)[0]
        self.assertAlmostEqual(slope, -0.250, delta=0.04)  # m/s, the 2F-140's top speed
        joint = self.gripper_joints.next_after(time.monotonic())
        self.assertEqual(joint.name, ['finger_joint'])
        upper = self.model.joints['finger_joint'].upper
        self.assertAlmostEqual(joint.position[0], upper, places=6)  # closed = the joint's upper limit
        angles = [m.position[0] for m in self.gripper_joints.since(t0)]
        self.assertTrue(all(b >= a - 1e-12 for a, b in zip(angles, angles[1:])), 'closing is monotonic')

    def test_bad_commands_are_ignored_with_one_warning_each(self):
        self.command.publish(Float64(0.07))
        self.wait_opening(0.07)
        for value in [float('nan'), float('inf'), -0.01, 0.5, 1e9, float('nan')]:
            self.command.publish(Float64(value))
            time.sleep(0.05)
        time.sleep(0.5)
        openings = [m.data for m in self.opening.since(time.monotonic() - 0.5)]
        self.assertTrue(openings and all(o == 0.07 for o in openings), openings[-5:])
        warnings = self.warnings_from('/gripper_sim', 'ignored gripper/command')
        self.assertEqual(len(warnings), 4, warnings)  # nan, inf, below 0, above the stroke
        self.assertTrue(all('between 0.0 (closed) and 0.14 (open)' in w for w in warnings))


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'sim_devices', SimDevicesTest)
