#!/usr/bin/env python3
"""rostest node: the 2F-140's register interface, spoken as Robotiq documents it (gripper_registers.test)."""
import time
import unittest

import rospkg
import rospy
import rostest
import tf2_ros
import yaml
from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input, Robotiq2FGripper_robot_output

from ur3_ft_gripper_description.devices import gripper_model
from ur3_ft_gripper_testing import rostest_helpers
from ur3_ft_gripper_testing.rostest_helpers import TIMEOUT

# A gap of P m ends within one count of the position register (0.140 m / 227
# counts = 0.62 mm; the mapping truncates to a whole count) plus the finger
# angle table's error (< 1e-6 rad): 0.7 mm.
GAP_TOLERANCE = 0.0007
# gSTA (manual 4.2): 0 reset, 1 activation in progress, 3 activation completed.
RESET, ACTIVATING, ACTIVE = 0, 1, 3
# gOBJ: 0 fingers in motion, 2 stopped by an object while closing, 3 at the requested position.
MOVING, AT_REQUESTED_POSITION = 0, 3


class RegisterClient(object):
    """Sends Robotiq2FGripperRobotOutput and reads Robotiq2FGripperRobotInput, as Robotiq's driver topics are."""

    def __init__(self):
        self.publisher = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output,
                                         queue_size=1)
        self.statuses = rostest_helpers.Recorder('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input)
        rostest_helpers.wait_for_subscribers(self.publisher)

    def send(self, **registers):
        self.publisher.publish(Robotiq2FGripper_robot_output(**registers))
        return time.monotonic()

    def wait_status(self, check, since=None, timeout=TIMEOUT):
        """The first status received after `since` (default: now) for which `check` holds."""
        start = time.monotonic() if since is None else since
        try:
            return rostest_helpers.wait_for(lambda: next((s for s in self.statuses.since(start) if check(s)), None),
                                            'a gripper status that matches', timeout, step=0.01)
        except AssertionError as e:
            last = self.statuses.since(0.0)[-1:] or ['nothing']
            raise AssertionError('%s; last status:\n%s' % (e, last[0])) from None

    def reset(self):
        return self.wait_status(lambda s: s.gACT == 0 and s.gSTA == RESET, since=self.send())

    def activate(self):
        """rACT 1 with the motion registers Robotiq's examples send with it."""
        return self.send(rACT=1, rGTO=1, rSP=255, rFR=150)


class GripperRegistersTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('gripper_registers_check')
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        cls.fingers = gripper_model.GripperKinematics(rospy.get_param('robot_description'))
        cls.gripper = RegisterClient()

    def setUp(self):
        self.gripper.reset()

    def active_and_open(self):
        sent = self.gripper.activate()
        return self.gripper.wait_status(lambda s: s.gSTA == ACTIVE and s.gOBJ == AT_REQUESTED_POSITION,
                                        since=sent)

    def test_activation_runs_through_in_progress_to_completed(self):
        sent = self.gripper.activate()
        activating = self.gripper.wait_status(lambda s: s.gSTA == ACTIVATING, since=sent)
        # rGTO 1 sent with rACT waits for the activation: "action delayed" until then.
        self.assertEqual((activating.gACT, activating.gFLT), (1, 0x05))
        done = self.gripper.wait_status(lambda s: s.gSTA == ACTIVE, since=sent)
        self.assertEqual((done.gACT, done.gGTO, done.gFLT), (1, 1, 0))
        opened = self.gripper.wait_status(lambda s: s.gOBJ == AT_REQUESTED_POSITION, since=sent)
        self.assertEqual((opened.gPR, opened.gPO), (0, 3))

    def test_motion_before_activation_is_refused_with_the_activation_fault(self):
        before = self.gripper.wait_status(lambda s: True)
        sent = self.gripper.send(rACT=0, rGTO=1, rPR=255, rSP=255)
        refused = self.gripper.wait_status(lambda s: s.gFLT != 0, since=sent)
        time.sleep(0.5)
        later = self.gripper.wait_status(lambda s: True)
        self.assertEqual((refused.gFLT, refused.gSTA), (0x07, RESET))
        self.assertEqual((later.gFLT, later.gPO), (0x07, before.gPO))  # the fingers did not move

    def test_close_and_open_report_motion_then_the_requested_position(self):
        self.active_and_open()
        sent = self.gripper.send(rACT=1, rGTO=1, rPR=255, rSP=255, rFR=150)
        moving = self.gripper.wait_status(lambda s: s.gOBJ == MOVING, since=sent)
        self.assertEqual((moving.gPR, moving.gGTO), (255, 1))
        # A status received after the request may still be one the gripper sent before it took effect
        # (at the request before): the one at the new request is the first to echo it.
        closed = self.gripper.wait_status(lambda s: s.gPR == 255 and s.gOBJ == AT_REQUESTED_POSITION, since=sent)
        self.assertEqual((closed.gPR, closed.gPO, closed.gFLT), (255, 230, 0))
        sent = self.gripper.send(rACT=1, rGTO=1, rPR=0, rSP=255, rFR=150)
        opened = self.gripper.wait_status(lambda s: s.gPR == 0 and s.gOBJ == AT_REQUESTED_POSITION, since=sent)
        self.assertEqual(opened.gPO, 3)

    def test_stop_holds_the_fingers_where_they_are(self):
        self.active_and_open()
        sent = self.gripper.send(rACT=1, rGTO=1, rPR=255, rSP=0, rFR=150)  # slowest closing
        self.gripper.wait_status(lambda s: s.gPO > 20, since=sent)
        sent = self.gripper.send(rACT=1, rGTO=0, rPR=255, rSP=0, rFR=150)
        stopped = self.gripper.wait_status(lambda s: s.gGTO == 0, since=sent)
        time.sleep(0.5)
        later = self.gripper.wait_status(lambda s: True)
        self.assertEqual(later.gPO, stopped.gPO)
        self.assertLess(later.gPO, 230)

    def test_gaps_of_the_action_server_mapping_put_the_pads_that_far_apart_in_tf(self):
        config = rospkg.RosPack().get_path('ur3_ft_gripper_description') + '/config/gripper_action_server.yaml'
        with open(config) as f:
            gaps = yaml.safe_load(f)
        count = (gaps['max_gap'] - gaps['min_gap']) / 255.0
        self.active_and_open()
        for position in (0.070, 0.030, 0.120):
            request = int((gaps['max_gap'] - position) / count)  # goalToRegisterState's mapping
            sent = self.gripper.send(rACT=1, rGTO=1, rPR=request, rSP=255, rFR=150)
            final = self.gripper.wait_status(
                lambda s: s.gPR == request and s.gOBJ == AT_REQUESTED_POSITION, since=sent)
            # TF follows through gripper_joint_states, joint_state_publisher and
            # robot_state_publisher: wait until it shows the final status.
            rostest_helpers.wait_for(
                lambda: abs(rostest_helpers.pad_gap(self.buffer, self.fingers) - position) <= GAP_TOLERANCE,
                'the pads %g m apart in TF (rPR %d, gPO %d)' % (position, request, final.gPO))


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'gripper_registers', GripperRegistersTest)
