#!/usr/bin/env python3
"""rostest node: Robotiq's client tools and action server against the simulated gripper (gripper_upstream.test)."""
import importlib.util
import os
import queue
import subprocess
import sys
import threading
import time
import unittest

import actionlib
import rospkg
import rospy
import rostest
import tf2_ros
from control_msgs.msg import GripperCommandAction, GripperCommandGoal
from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input, Robotiq2FGripper_robot_output

import rostest_helpers
from rostest_helpers import TIMEOUT
from ur3_ft_gripper_description.devices import gripper_model
# A goal of P m ends within one count of the position register (0.140 m / 227
# counts = 0.62 mm; the action server truncates to a whole count) plus the
# finger angle table's error (< 1e-6 rad): 0.7 mm.
GAP_TOLERANCE = 0.0007


def jr_robotics_tools():
    """robotiq_2f_gripper_control of the jr-robotics (Python 3) variant, found by path."""
    path = os.path.realpath(rospkg.RosPack().get_path('robotiq_2f_gripper_control'))
    upstream = os.environ.get('UR3_FT_GRIPPER_UPSTREAM') or os.path.dirname(os.path.dirname(path))
    return os.path.join(upstream, 'robotiq-noetic', 'robotiq_2f_gripper_control')


TOOLS = jr_robotics_tools()


def load_robotiq_cgripper():
    path = os.path.join(TOOLS, 'src', 'robotiq_2f_gripper_control', 'robotiq_2f_gripper_ctrl.py')
    spec = importlib.util.spec_from_file_location('jr_robotiq_2f_gripper_ctrl', path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.RobotiqCGripper


def status():
    return rospy.wait_for_message('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input, TIMEOUT)


def wait_status(check, timeout=TIMEOUT):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        s = status()
        if check(s):
            return s
    raise AssertionError('the gripper status never matched; last:\n%s' % s)


class Lines(object):
    """A process's stdout lines, read in a thread."""

    def __init__(self, process):
        self.queue = queue.Queue()
        self.text = []
        threading.Thread(target=self._read, args=(process.stdout,), daemon=True).start()

    def _read(self, stream):
        for line in stream:
            self.text.append(line)
            self.queue.put(line)

    def wait_for(self, text, timeout=TIMEOUT):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                if text in self.queue.get(timeout=0.5):
                    return
            except queue.Empty:
                pass
        raise AssertionError('%r never printed; output:\n%s' % (text, ''.join(self.text[-40:])))


class GripperUpstreamTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('gripper_upstream_check')
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        cls.fingers = gripper_model.GripperKinematics(rospy.get_param('robot_description'))

    def reset(self, publisher):
        """Reset the gripper through `publisher`, once it reaches the simulated gripper."""
        end = time.monotonic() + TIMEOUT
        while publisher.get_num_connections() == 0 and time.monotonic() < end:
            time.sleep(0.05)
        publisher.publish(Robotiq2FGripper_robot_output())
        wait_status(lambda s: s.gACT == 0 and s.gSTA == 0)

    def pad_gap(self):
        return rostest_helpers.pad_gap(self.buffer, self.fingers)

    def test_simple_controller_resets_activates_closes_and_opens(self):
        controller = subprocess.Popen(
            [sys.executable, os.path.join(TOOLS, 'nodes', 'Robotiq2FGripperSimpleController.py'),
             '__name:=simple_controller'],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            universal_newlines=True, bufsize=1)
        lines = Lines(controller)
        try:
            steps = [('r', lambda s: s.gACT == 0 and s.gSTA == 0),
                     ('a', lambda s: s.gSTA == 3 and s.gOBJ == 3 and s.gPO == 3),
                     ('c', lambda s: s.gPR == 255 and s.gOBJ == 3 and s.gPO == 230),
                     ('o', lambda s: s.gPR == 0 and s.gOBJ == 3 and s.gPO == 3)]
            for key, reached in steps:
                # Its publisher may not be connected yet when it sends: send again until seen.
                end = time.monotonic() + TIMEOUT
                while True:
                    lines.wait_for('Current command:')  # then it prompts, without a newline
                    controller.stdin.write(key + '\n')
                    controller.stdin.flush()
                    try:
                        wait_status(reached, timeout=5.0)
                        break
                    except AssertionError:
                        self.assertLess(time.monotonic(), end, 'command %r had no effect' % key)
        finally:
            controller.kill()
            controller.wait()

    def test_status_listener_prints_the_status(self):
        command = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output,
                                  queue_size=1)
        self.reset(command)
        command.publish(Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=0, rSP=255, rFR=150))
        wait_status(lambda s: s.gSTA == 3 and s.gOBJ == 3)
        listener = subprocess.Popen(
            [sys.executable, os.path.join(TOOLS, 'nodes', 'Robotiq2FGripperStatusListener.py'),
             '__name:=status_listener'],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, bufsize=1)
        lines = Lines(listener)
        try:
            lines.wait_for('gSTA = 3: Activation is completed')
            lines.wait_for('gOBJ = 3: Fingers are at requested position')
            lines.wait_for('gFLT = 0: No Fault')
            lines.wait_for('gPO = 3: Position of Fingers: 3/255')
        finally:
            listener.kill()
            listener.wait()

    def test_robotiq_cgripper(self):
        gripper = load_robotiq_cgripper()()
        self.assertTrue(gripper.wait_for_connection(TIMEOUT))
        self.reset(gripper.cmd_pub)
        self.assertTrue(gripper.is_reset())
        self.assertTrue(gripper.activate(timeout=TIMEOUT))
        self.assertTrue(gripper.is_ready())
        self.assertTrue(gripper.close(block=True, timeout=TIMEOUT))
        wait_status(lambda s: s.gPO == 230)
        self.assertTrue(gripper.is_closed() and not gripper.object_detected())
        self.assertTrue(gripper.open(block=True, timeout=TIMEOUT))
        wait_status(lambda s: s.gPO == 3)
        self.assertTrue(gripper.is_opened())
        self.assertTrue(gripper.stop(block=True, timeout=TIMEOUT))

    def test_action_goal_ends_with_the_pads_that_far_apart_in_tf(self):
        command = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output,
                                  queue_size=1)
        self.reset(command)
        command.publish(Robotiq2FGripper_robot_output(rACT=1))  # the server takes goals when active
        wait_status(lambda s: s.gSTA == 3)
        client = actionlib.SimpleActionClient('gripper', GripperCommandAction)
        self.assertTrue(client.wait_for_server(rospy.Duration(TIMEOUT)))
        for position in (0.070, 0.030, 0.120):
            goal = GripperCommandGoal()
            goal.command.position, goal.command.max_effort = position, 50.0
            client.send_goal(goal)
            self.assertTrue(client.wait_for_result(rospy.Duration(TIMEOUT)), position)
            self.assertEqual(client.get_state(), actionlib.GoalStatus.SUCCEEDED, position)
            self.assertTrue(client.get_result().reached_goal, position)
            # TF follows through gripper_joint_states, joint_state_publisher and
            # robot_state_publisher: wait until it shows the final status.
            final = status()
            end = time.monotonic() + TIMEOUT
            while time.monotonic() < end:
                gap = self.pad_gap()
                if abs(gap - position) <= GAP_TOLERANCE:
                    break
                time.sleep(0.05)
            self.assertAlmostEqual(gap, position, delta=GAP_TOLERANCE, msg='gPO %d' % final.gPO)


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'gripper_upstream', GripperUpstreamTest)
