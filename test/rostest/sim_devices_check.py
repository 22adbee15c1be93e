#!/usr/bin/env python3
"""rostest node: ft300_sim and gripper_sim against the real model, TF and master (sim_devices.test).

With --physics (sim_devices_physics.test) the same interface tests run on the physics cell, in the
bring-up with sim:=true physics:=true: the arm's pose then comes from the arm (moved through
scaled_pos_joint_traj_controller) rather than from this node's joint_states, and the readings at
rest are judged within 0.5 % of the gripper's weight (the servos hold the arm, they do not freeze it).
The tests of what only the kinematic devices have (~payload_mass, ~object_width, TF going stale or
missing) are not in that suite: PhysicsDevicesTest below.
"""
import math
import sys
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
from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input, Robotiq2FGripper_robot_output
from robotiq_ft_sensor.msg import ft_sensor
from robotiq_ft_sensor.srv import sensor_accessor

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices import gripper_model
from ur3_ft_gripper_description.model import inertials
from ur3_ft_gripper_testing import rostest_helpers
from ur3_ft_gripper_testing.rostest_helpers import TIMEOUT, Recorder

G = 9.80665
# FT 300 manual (config/robotiq_mass.yaml): FT 300 + 2F-140 1275 g, FT 300 alone 300 g.
MANUAL_GRIPPER_MASS = 0.975
OBJECT_MASS, OBJECT_COM = 0.5, np.array([0.0, 0.0, 0.2])        # sim_devices.test
ARM = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint',
       'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint']
# Sensor z axis straight down (checked against the model in the test).
TOOL_DOWN = [0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0]
ZERO = [0.0] * 6  # the gripper points along base_link +y: horizontal
SENSOR = 'robotiq_ft_frame_id'
# The stream's resolution, 0.01 N and 0.001 Nm: a reading is within half a count of the exact wrench.
FORCE_ATOL, TORQUE_ATOL = 0.0051, 0.00051
PHYSICS = '--physics' in sys.argv
if PHYSICS:
    # A held arm at rest on physics (test/physics: within 0.5 % of the tool side's weight, 10 % of that in N m).
    FORCE_ATOL, TORQUE_ATOL = 0.05, 0.005
# The other pose: the kinematic devices take any (the gripper horizontal); on physics one the arm
# reaches from TOOL_DOWN without touching the table, the tool tilted.
OTHER = [0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2 + 0.6, 0.4] if PHYSICS else [0.0] * 6


# The tests that do not zero the sensor read the unit's offset beside the load.
UNIT_FORCE, UNIT_TORQUE = np.split(rostest_helpers.FT300_UNIT_OFFSET, 2)


def expected_wrench(rotation, mass, com):
    """Weight of `mass` at `com` (sensor frame) on a sensor with orientation `rotation` in a z-up frame."""
    force = mass * G * rotation.T.dot([0.0, 0.0, -1.0])
    return force, np.cross(com, force)


def unzeroed(force, torque):
    """A wrench as a sensor never zeroed reads it: with the unit's offset."""
    return force + UNIT_FORCE, torque + UNIT_TORQUE


def wrench_values(msg):
    """A WrenchStamped's six values, force then torque."""
    return np.concatenate(wrench_arrays(msg))


def stream_values(msg):
    """A robotiq_ft_sensor message's six values, force then torque."""
    return [msg.Fx, msg.Fy, msg.Fz, msg.Mx, msg.My, msg.Mz]


def split_at_the_first_zeroed(messages, values, atol):
    """(the messages before the first that reads zero, it and those after), once ten read from it on; else None."""
    first = next((i for i, m in enumerate(messages) if np.allclose(values(m), 0.0, atol=atol)), None)
    return (messages[:first], messages[first:]) if first is not None and len(messages) - first >= 10 else None


def wrench_arrays(msg):
    w = msg.wrench
    return (np.array([w.force.x, w.force.y, w.force.z]),
            np.array([w.torque.x, w.torque.y, w.torque.z]))


class SimDevicesTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('sim_devices_check')
        cls.model = kinematics.Model(rospy.get_param('robot_description'))
        # The load the sensor must feel is the model's own gripper (its inertials).
        cls.gripper_mass, cls.gripper_com = inertials.mass_below(cls.model, SENSOR)
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        cls.arm = list(TOOL_DOWN)
        cls.publishing = threading.Event()
        cls.publishing.set()
        cls.joint_publisher = rospy.Publisher('joint_states', JointState, queue_size=10)
        cls.wrench = Recorder('robotiq_ft_wrench', WrenchStamped)
        cls.loaded = Recorder('loaded/robotiq_ft_wrench', WrenchStamped)
        cls.zeroing = Recorder('zeroing/robotiq_ft_wrench', WrenchStamped)
        cls.stream = Recorder('robotiq_ft_sensor', ft_sensor)
        cls.zeroing_stream = Recorder('zeroing/robotiq_ft_sensor', ft_sensor)
        cls.no_tf = Recorder('no_tf/robotiq_ft_wrench', WrenchStamped)
        cls.no_tf_stream = Recorder('no_tf/robotiq_ft_sensor', ft_sensor)
        cls.rosout = Recorder('/rosout', Log)  # straight from the nodes: no rosout node needed
        # The bring-up remaps gripper_joint_states' topic onto joint_states, beside the arm's.
        cls.gripper_joints = Recorder('joint_states', JointState, keep=lambda m: m.name == ['finger_joint']) \
            if PHYSICS else Recorder('gripper/joint_states', JointState)
        cls.gripper_status = Recorder('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input)
        cls.holding_status = Recorder('holding/Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input)
        cls.real_joints = Recorder('real_unit/gripper/joint_states', JointState)
        cls.command = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output,
                                      queue_size=10)
        cls.holding_command = rospy.Publisher('holding/Robotiq2FGripperRobotOutput',
                                              Robotiq2FGripper_robot_output, queue_size=10)
        cls.real_status = rospy.Publisher('real_unit/Robotiq2FGripperRobotInput',
                                          Robotiq2FGripper_robot_input, queue_size=300)
        cls.fingers = gripper_model.GripperKinematics(rospy.get_param('robot_description'))
        cls.settled = rospy.Time(0)  # on physics: the cell's time the arm has rested a second at its target
        if PHYSICS:
            from ur3_ft_gripper_description import clients
            cls.ur_arm = clients.UrArm(rospy)
            cls.arm_joints = Recorder('joint_states', JointState, keep=lambda m: ARM[0] in m.name)
        else:
            threading.Thread(target=cls._publish_joints, daemon=True).start()
        for publisher in (cls.command, cls.real_status) + (() if PHYSICS else (cls.holding_command,)):
            rostest_helpers.wait_for_subscribers(publisher)

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

    def lookup(self, target, source, stamp=None):
        return rostest_helpers.lookup(self.buffer, target, source, stamp=stamp)

    def move_to(self, arm):
        """Publish `arm`, wait until TF shows it; returns the sensor's orientation in base_link.

        On physics: move the arm there through its trajectory controller, let it settle, and return
        the orientation TF shows then (the servos hold it within a fraction of a milliradian).
        """
        if PHYSICS:
            sent = time.monotonic()
            self.ur_arm.move_steadily(arm)
            # A second of the cell's clock from the arm's first joint state at rest at the target. Not a second
            # of this node's clock from now: on a busy machine this node's clock trails the cell's, by more
            # when the move ends than a second later, and its second is then less of the arm at rest.
            type(self).settled = self.at_rest(arm, sent) + rospy.Duration(1.0)
            # TF at that moment: this node's listener may trail the cell, and the latest it has be the last pose.
            return self.lookup('base_link', SENSOR, stamp=self.settled)[:3, :3]
        type(self).arm = list(arm)
        expected = self.model.transform('base_link', SENSOR, dict(zip(ARM, arm)))

        def shown():
            try:
                return np.allclose(self.lookup('base_link', SENSOR), expected, atol=1e-6)
            except tf2_ros.TransformException:
                return False
        rostest_helpers.wait_for(shown, 'TF to show the commanded arm pose %s' % arm, step=0.02)
        return expected[:3, :3]

    def at_rest(self, arm, since):
        """The stamp of the first joint state received after `since` (monotonic s) with the arm at rest at `arm`.

        One publisher's messages arrive in the order it sent them, so every state of the move before it has
        arrived too."""
        def found():
            for m in self.arm_joints.since(since):
                q = [m.position[m.name.index(j)] for j in ARM]
                qd = [m.velocity[m.name.index(j)] for j in ARM]
                if np.allclose(q, arm, atol=2e-3) and np.allclose(qd, 0.0, atol=1e-2):
                    return m.header.stamp
            return None
        return rostest_helpers.wait_for(found, 'a joint state of the arm at rest at %s' % arm)

    def reading(self, recorder):
        """The first wrench computed after now (one sensor period of margin). On physics, the first measured
        after now on the cell's clock, and after the arm has settled: on a busy machine the node publishes
        samples of the moments before late. A reading stamped then also means the sensor's node has reached
        that time, so that a SET_ZERO sent after it is taken there or later."""
        if PHYSICS:
            return wrench_arrays(recorder.stamped_after(max(rospy.Time.now(), self.settled)))
        return wrench_arrays(recorder.next_after(time.monotonic() + 0.05))

    def warnings_from(self, node, text):
        return rostest_helpers.logs(self.rosout, node, Log.WARN, text)

    # -- ft300_sim -------------------------------------------------------------

    def test_robot_description_as_loaded_has_an_inertial_on_every_link_but_the_root(self):
        bare = [link.name for link in self.model.robot.links if link.inertial is None]
        self.assertEqual(bare, [self.model.root()])

    def test_the_models_gripper_has_the_manuals_mass_on_the_sensor_axis(self):
        self.assertAlmostEqual(self.gripper_mass, MANUAL_GRIPPER_MASS, delta=1e-4)  # + gripper_tcp's 10 mg
        np.testing.assert_allclose(self.gripper_com[:2], 0.0, atol=2e-4)
        self.assertGreater(self.gripper_com[2], 0.03)

    def test_tool_pointing_down_reads_the_gripper_weight_along_plus_z(self):
        rotation = self.move_to(TOOL_DOWN)
        self.assertAlmostEqual(rotation[2, 2], -1.0, places=6, msg='TOOL_DOWN must point the sensor down')
        force, torque = self.reading(self.wrench)
        expected_force, expected_torque = unzeroed(np.array([0.0, 0.0, self.gripper_mass * G]),
                                                   expected_wrench(rotation, self.gripper_mass, self.gripper_com)[1])
        np.testing.assert_allclose(force, expected_force, atol=FORCE_ATOL)
        np.testing.assert_allclose(torque, expected_torque, atol=TORQUE_ATOL)

    def test_wrench_follows_the_pose_in_tf(self):
        rng = np.random.default_rng(7)
        for arm in [ZERO] + [list(rng.uniform(-math.pi, math.pi, 6)) for _ in range(4)]:
            rotation = self.move_to(arm)
            expected_force, expected_torque = unzeroed(*expected_wrench(rotation, self.gripper_mass,
                                                                        self.gripper_com))
            # The sensor's node sees the new pose through its own TF listener, later than this node when
            # the machine is busy (past the tolerance once, in a fresh root at load 12): the readings of the next
            # few seconds, until one shows it. A wrong gravity model never does.
            deadline = time.monotonic() + 10.0
            while True:
                force, torque = self.reading(self.wrench)
                if time.monotonic() > deadline or (np.allclose(force, expected_force, atol=FORCE_ATOL) and
                                                   np.allclose(torque, expected_torque, atol=TORQUE_ATOL)):
                    break
            np.testing.assert_allclose(force, expected_force, atol=FORCE_ATOL, err_msg=str(arm))
            np.testing.assert_allclose(torque, expected_torque, atol=TORQUE_ATOL, err_msg=str(arm))

    def test_held_object_adds_its_weight_and_lever(self):
        self.move_to(TOOL_DOWN)
        force, _ = self.reading(self.loaded)
        self.assertAlmostEqual(force[2] - UNIT_FORCE[2], (self.gripper_mass + OBJECT_MASS) * G, delta=FORCE_ATOL)
        self.move_to(ZERO)  # horizontal: the weight acts on the combined lever arm
        torque = self.reading(self.loaded)[1] - UNIT_TORQUE
        lever = self.gripper_mass * self.gripper_com[2] + OBJECT_MASS * OBJECT_COM[2]
        self.assertAlmostEqual(np.linalg.norm(torque), lever * G, delta=2 * TORQUE_ATOL)

    def test_both_topics_carry_the_same_values_in_the_devices_resolution(self):
        self.move_to(OTHER)
        start = time.monotonic()
        # Waits for the readings, not for a time: a node starved by a busy machine publishes late.
        rostest_helpers.wait_for(lambda: len(self.wrench.since(start)) > 10, 'robotiq_ft_wrench readings', TIMEOUT)
        wrenches = self.wrench.since(start)
        # One reading of robotiq_ft_sensor received after them: the node has published each pair's other
        # half before it, and a connection delivers in order.
        self.stream.next_after(time.monotonic())
        streams = {(m.Fx, m.Fy, m.Fz, m.Mx, m.My, m.Mz) for m in self.stream.since(start)}
        self.assertGreater(len(wrenches), 10)
        for msg in wrenches:
            force, torque = wrench_arrays(msg)
            values = tuple(force) + tuple(torque)
            self.assertIn(values, streams)  # float32 values, exactly the same
            counts = np.array(values) / np.array([0.01] * 3 + [0.001] * 3)
            np.testing.assert_allclose(counts, np.round(counts), atol=1e-3)
            self.assertEqual(msg.header.frame_id, SENSOR)

    def test_set_zero_makes_later_readings_on_both_topics_relative(self):
        # On physics the one sensor of the cell: zeroed last among its tests (by name), so that the
        # others read it unzeroed.
        namespace, wrench, stream = ('', self.wrench, self.stream) if PHYSICS else (
            'zeroing/', self.zeroing, self.zeroing_stream)
        if PHYSICS:
            # The fingers open, as the model's load has them: closed, they carry their mass further out.
            self.activate(self.command, self.gripper_status)
        acc = rospy.ServiceProxy(namespace + 'robotiq_ft_sensor_acc', sensor_accessor)
        acc.wait_for_service(TIMEOUT)
        first = self.move_to(OTHER)
        self.reading(wrench)  # a reading at this pose exists before zeroing
        reply = acc(command_id=8, command='')
        self.assertEqual((reply.success, reply.res), (True, 'Done'))
        replied = time.monotonic()
        # The reading before the request became the zero: exact on the kinematic devices, within
        # what a held arm moves in 10 ms on physics.
        atol = 1e-6 if not PHYSICS else 0.02
        if PHYSICS:
            # The request's time is the node's on the cell's clock, which this process's may trail: the node
            # may still send readings of the moments before it, unzeroed. Every one of those comes before
            # the first zeroed reading, and every reading from that one on reads zero.
            before, after = rostest_helpers.wait_for(
                lambda: split_at_the_first_zeroed(wrench.since(replied), wrench_values, atol),
                'ten robotiq_ft_wrench readings from the first zeroed one')
            np.testing.assert_allclose([wrench_values(m) for m in after], 0.0, atol=atol)
            self.assertLess(max([m.header.stamp for m in before] or [rospy.Time(0)]), after[0].header.stamp)
        else:
            force, torque = self.reading(wrench)
            np.testing.assert_allclose(np.concatenate([force, torque]), 0.0, atol=atol)
        # The stream's messages carry no stamp, and on a busy machine one the node sent before the zeroing can
        # arrive after the reply: from its first zeroed message on, every message reads zero.
        _, zeroed = rostest_helpers.wait_for(
            lambda: split_at_the_first_zeroed(stream.since(replied), stream_values, atol),
            'ten stream messages from the first zeroed one')
        zeroed = [stream_values(m) for m in zeroed]
        np.testing.assert_allclose(zeroed, 0.0, atol=atol)
        second = self.move_to(TOOL_DOWN)
        force, torque = self.reading(wrench)
        f1, t1 = expected_wrench(first, self.gripper_mass, self.gripper_com)
        f2, t2 = expected_wrench(second, self.gripper_mass, self.gripper_com)
        np.testing.assert_allclose(force, f2 - f1, atol=2 * FORCE_ATOL)
        np.testing.assert_allclose(torque, t2 - t1, atol=2 * TORQUE_ATOL)

    def test_accessor_answers_as_rq_sensor(self):
        acc = rospy.ServiceProxy('robotiq_ft_sensor_acc', sensor_accessor)
        acc.wait_for_service(TIMEOUT)
        answers = {1: (True, 'SIM-0001'), 2: (True, 'FTS-0.0.0'), 4: (True, '2026'),
                   3: (False, 'Unsupported command_id'), 0: (False, 'Unsupported command_id'),
                   255: (False, 'Unsupported command_id')}
        for command_id, expected in answers.items():
            reply = acc(command_id=command_id, command='')
            self.assertEqual((reply.success, reply.res), expected, command_id)
        legacy = {'GET SNU': 'SIM-0001', 'GET FWV': 'FTS-0.0.0', 'GET PYE': '2026', 'GET XYZ': ''}
        for command, res in legacy.items():
            reply = acc(command_id=1, command=command)  # the string wins
            self.assertEqual((reply.success, reply.res), (False, res), command)
        # A last unsupported id as a fence: the node's earlier warnings arrive before its warning.
        acc(command_id=254, command='')
        rostest_helpers.wait_for_log(self.rosout, '/robotiq_ft_sensor', Log.WARN, "Unsupported command_id '254'")
        deprecated = self.warnings_from('/robotiq_ft_sensor', 'command-string is deprecated')
        self.assertEqual(len(deprecated), 1, deprecated)
        unsupported = self.warnings_from('/robotiq_ft_sensor', "Unsupported command_id '3'")
        self.assertEqual(len(unsupported), 1, unsupported)

    def test_frame_unknown_to_tf_waits_warns_once_and_publishes_nothing(self):
        # Started from here, after the /rosout subscription, so that no warning can be missed.
        # The sensor frame must be a link of the model, whose load it carries:
        # the gravity frame is the unknown one.
        rospy.set_param('no_tf/robotiq_ft_sensor/gravity_frame', 'no_such_world_frame')
        launch = roslaunch.scriptapi.ROSLaunch()
        launch.start()
        try:
            process = launch.launch(roslaunch.core.Node(
                'ur3_ft_gripper_description', 'ft300_sim', name='robotiq_ft_sensor', namespace='/no_tf/'))
            acc = rospy.ServiceProxy('no_tf/robotiq_ft_sensor_acc', sensor_accessor)
            acc.wait_for_service(TIMEOUT)
            time.sleep(4.0)  # a window to observe: no wrench, and no second warning
            self.assertTrue(process.is_alive())
            self.assertEqual(acc(command_id=1, command='').res, 'SIM-0001')  # serving meanwhile
            self.assertEqual(self.no_tf.since(0), [])
            self.assertEqual(self.no_tf_stream.since(0), [])
            # An unsupported id as a fence: the node's earlier warnings arrive before its warning.
            acc(command_id=254, command='')
            rostest_helpers.wait_for_log(self.rosout, '/no_tf/robotiq_ft_sensor', Log.WARN,
                                         "Unsupported command_id '254'")
            warnings = self.warnings_from('/no_tf/robotiq_ft_sensor', 'waiting for TF')
            self.assertEqual(len(warnings), 1, warnings)
            self.assertIn('no_such_world_frame', warnings[0])
        finally:
            launch.stop()

    def test_stale_pose_stops_the_wrench_until_tf_updates(self):
        self.move_to(ZERO)
        paused = rospy.get_time()
        self.publishing.clear()
        try:
            time.sleep(1.5)  # ~max_pose_age (0.5 s) plus margin
            quiet_since = time.monotonic()
            time.sleep(1.0)
            self.assertEqual(self.wrench.since(quiet_since), [], 'published for a stale pose')
        finally:
            resumed = rospy.get_time()
            self.publishing.set()
        # Resumed, and said so: every warning before that message has arrived.
        self.wrench.next_after(time.monotonic())
        rostest_helpers.wait_for_log(self.rosout, '/robotiq_ft_sensor', Log.INFO, 'robotiq_ft_wrench at', quiet_since)
        # Once for the pause, by the node's own log stamps: on a busy machine this node's publisher can
        # starve past the age limit elsewhere too, and the sensor rightly warns then as well.
        warnings = [m.msg for m in self.rosout.since(0) if m.name == '/robotiq_ft_sensor' and m.level == Log.WARN
                    and 's old' in m.msg and paused <= m.header.stamp.to_sec() <= resumed]
        self.assertEqual(len(warnings), 1, [(m.header.stamp.to_sec(), m.level, m.msg) for m in self.rosout.since(0)
                                            if m.name == '/robotiq_ft_sensor'])

    # -- gripper_sim and gripper_joint_states ---------------------------------------

    def wait_status(self, recorder, check):
        return rostest_helpers.wait_for(lambda: (lambda msg: msg if check(msg) else None)(
            recorder.next_after(time.monotonic())), 'a gripper status that matches', step=0)

    def activate(self, publisher, recorder):
        publisher.publish(Robotiq2FGripper_robot_output())
        self.wait_status(recorder, lambda s: s.gSTA == 0)
        publisher.publish(Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=0, rSP=255, rFR=150))
        self.wait_status(recorder, lambda s: s.gSTA == 3 and s.gOBJ == 3)

    def test_gripper_closes_at_its_speed_and_the_joint_reaches_closed(self):
        self.activate(self.command, self.gripper_status)
        t0 = time.monotonic()
        # At rSP 0, the slowest. (test/physics checks the pads' speed at rSP 0, 128 and 255 on the cell's
        # own clock.)
        self.command.publish(Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=255, rSP=0, rFR=150))
        self.wait_status(self.gripper_status, lambda s: s.gPO == 230 and s.gOBJ == 3)
        scale = gripper_model.RegisterScale(0.140, 3, 230)  # config/sim_devices.yaml
        if rospy.get_param('/use_sim_time', False):
            # On the simulated clock the node publishes one status per 50th of a simulated second, each
            # the fingers at its own time however late it runs: the statuses are the clock. (The joint's
            # stamps are its relay's receipt times: on a busy machine, with the clock running ahead,
            # they fell behind by 0.8 s over the stroke once.)
            period = 1.0 / rospy.get_param('robotiq2FGripper/rate', 50.0)
            statuses = [m for m in self.gripper_status.since(t0) if m.gPR == 255]
            openings = [(n * period, scale.opening(m.gPO)) for n, m in enumerate(statuses)]
        else:
            # The pads' gap over the finger joint's stamps (ROS time), relayed as they come.
            openings = [(m.header.stamp.to_sec(), self.fingers.opening(m.position[0]))
                        for m in self.gripper_joints.since(t0)]
        moving = [(t, o) for t, o in openings if scale.opening(210) < o < scale.opening(20)]
        self.assertGreater(len(moving), 10)
        slope = np.polyfit([t - moving[0][0] for t, _ in moving], [o for _, o in moving], 1)[0]
        self.assertAlmostEqual(slope, -0.030, delta=0.005)  # m/s, the 2F-140's slowest, at rSP 0
        # gripper_joint_states turns each status into a joint state as it comes. On a busy machine it may
        # run a second of the stroke behind the statuses, so wait for its state of the closed status (pads
        # touching), not for a fixed delay.
        joint = rostest_helpers.wait_for(
            lambda: next((m for m in self.gripper_joints.since(t0)
                          if abs(self.fingers.opening(m.position[0])) < 1e-6), None),
            lambda: 'finger_joint with the pads touching (last opening: %s m)' % (
                [round(self.fingers.opening(m.position[0]), 4) for m in self.gripper_joints.since(t0)[-3:]],))
        self.assertEqual(joint.name, ['finger_joint'])
        # Closing never opens the pads again. On physics gPO is the pads' measured gap in register counts,
        # and a gap standing at a count's edge reads the counts either side of it, as a real unit's does.
        allowed = 1.0 / scale.counts_per_metre + 1e-9 if PHYSICS else 1e-9
        states = [(m.header.stamp.to_sec(), m.position[0]) for m in self.gripper_joints.since(t0)]
        reopened = [(t, a, b) for (_, a), (t, b) in zip(states, states[1:])
                    if self.fingers.opening(b) - self.fingers.opening(a) > allowed]
        self.assertEqual(reopened, [], 'the pads opened again (stamp, finger_joint before, after); closed at %s'
                         % (states[-1],))

    def test_closing_on_a_part_stops_at_its_width(self):
        self.activate(self.holding_command, self.holding_status)
        self.holding_command.publish(Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=255, rSP=255, rFR=255))
        held = self.wait_status(self.holding_status, lambda s: s.gOBJ == 2)
        self.assertAlmostEqual(gripper_model.RegisterScale(0.140, 3, 230).opening(held.gPO), 0.05, delta=0.0007)
        self.assertGreater(held.gCU, 0)

    def test_nonsense_registers_warn_once_and_act_as_the_driver_sends_them(self):
        self.activate(self.command, self.gripper_status)
        for _ in range(50):
            self.command.publish(Robotiq2FGripper_robot_output(rACT=5, rGTO=9, rPR=100, rSP=255, rFR=150))
        self.wait_status(self.gripper_status, lambda s: s.gPO == 100 and s.gOBJ == 3)
        # A reset with a nonsense rATR as a fence: the node's earlier warnings arrive before its warning.
        self.command.publish(Robotiq2FGripper_robot_output(rATR=2))
        rostest_helpers.wait_for_log(self.rosout, '/robotiq2FGripper', Log.WARN, 'rATR=2')
        for register in ('rACT=5', 'rGTO=9'):
            warnings = self.warnings_from('/robotiq2FGripper', register)
            self.assertEqual(len(warnings), 1, warnings)

    def test_joint_states_of_a_real_units_status_stream(self):
        scale = gripper_model.RegisterScale(0.140, 6, 227)  # the node's ~gpo_open, ~gpo_closed
        for gpo in [6, 0, 40, 116, 200, 227, 255] + list(range(6, 228, 7)):
            status = Robotiq2FGripper_robot_input(gACT=1, gGTO=1, gSTA=3, gOBJ=3, gPR=gpo, gPO=gpo)
            sent = time.monotonic()
            self.real_status.publish(status)
            joint = self.real_joints.next_after(sent)
            self.assertEqual(joint.name, ['finger_joint'])
            expected = min(scale.opening(gpo), self.fingers.max_opening)
            self.assertAlmostEqual(self.fingers.opening(joint.position[0]), expected, delta=1e-5, msg=gpo)


class PhysicsDevicesTest(SimDevicesTest):
    """The suite on physics: every test of the interface, not those of what only the kinematic devices have."""


for _name in ('test_wrench_follows_the_pose_in_tf',              # random poses: the table is in the way
              'test_held_object_adds_its_weight_and_lever',       # ~payload_mass: physics weighs what is held
              'test_frame_unknown_to_tf_waits_warns_once_and_publishes_nothing',  # no TF on physics
              'test_stale_pose_stops_the_wrench_until_tf_updates',
              'test_closing_on_a_part_stops_at_its_width'):       # ~object_width: physics_cell.test grasps
    setattr(PhysicsDevicesTest, _name, None)


def physics_suite():
    """PhysicsDevicesTest's tests, SET_ZERO last: on physics it zeroes the one sensor the others read."""
    names = unittest.TestLoader().getTestCaseNames(PhysicsDevicesTest)
    names.sort(key=lambda name: name.startswith('test_set_zero'))
    return unittest.TestSuite(PhysicsDevicesTest(name) for name in names)


if __name__ == '__main__':
    if PHYSICS:
        rostest.rosrun('ur3_ft_gripper_description', 'sim_devices_physics', '__main__.physics_suite')
    else:
        rostest.rosrun('ur3_ft_gripper_description', 'sim_devices', SimDevicesTest)
