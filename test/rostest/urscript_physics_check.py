#!/usr/bin/env python3
"""rostest node: URScript on script_command against the physics cell (urscript_physics.test).

Through the real interfaces only (script_command, robot_program_running,
rq_sensor, the robot's wrench, joint_states, the dashboard), judged by
MuJoCo's own contact force (the private link's `truth`) and by the tool's
path computed from the model:

- examples/force_mode_press.py's own press (its program, its readings) presses the tool on the table
  with 10, 20 and 40 N: the zeroed FT 300 reads the force within 5 % or
  0.5 N, so does MuJoCo's contact, and the robot's own wrench agrees with the
  FT 300 within 1 N;
- with x and y compliant too and no force asked there, the tool does not
  drift more than 1 mm/s;
- a movel keeps the tool within 1 mm of its line and ends within 0.5 mm;
- a program that does not compile is refused whole: rosout names its line;
- the example as a user runs it (`rosrun ... force_mode_press.py --forces 15`)
  exits 0 and prints the FT 300's and the robot's readings, in agreement.

The tests run in the order of their names.
"""
import re
import subprocess
import sys
import time
import unittest

import numpy as np
import rospy
import rostest
from rosgraph_msgs.msg import Log

from ur3_ft_gripper_description import clients
from ur3_ft_gripper_testing import rostest_helpers, shipped

force_mode_press = shipped.script('examples/force_mode_press.py')
HW = clients.HARDWARE_INTERFACE
FORCES = (10.0, 20.0, 40.0)


def say(text):
    print('[urscript_physics] %s' % text)
    sys.stdout.flush()


class UrscriptPhysicsTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('urscript_physics_check')
        cls.press = force_mode_press.ForceModePress(rospy, say=say)
        cls.truth_link = rostest_helpers.cell_link()
        cls.rosout = rostest_helpers.Recorder('/rosout', Log)  # straight from the nodes

    def tool_position(self):
        return self.press.tool.tool_pose(self.press.arm.joint_positions())[:3, 3]

    def contact_impulse(self):
        """(simulated time, MuJoCo's contacts' impulse on the robot since the cell began, N s)."""
        when, truth = self.truth_link.truth()
        return when, np.array(truth['contact_impulse'])

    def test_1_force_mode_presses_with_the_commanded_force(self):
        seen = []
        for force in FORCES:
            self.press.start(*force_mode_press.START_XY)
            # The example's own press; MuJoCo's contact over the same second as its readings: the mean
            # force from the impulse between the first and last samples (the force itself changes from
            # one timestep to the next: at 10 N its standard deviation is 1.8 N).
            result = self.press.press(force, 0.05, force_mode_press.SETTLE + force_mode_press.MEASURE,
                                      sample=self.contact_impulse)
            ft300, robot = result['ft300'], result['robot']
            (began, first), (ended, last) = result['samples'][0], result['samples'][-1]
            contact = (last - first) / (ended - began)
            seen.append('%g N: FT 300 fz %.2f, robot fz %.2f, contact z %.2f' % (
                force, ft300[2], robot[2], contact[2]))
            tolerance = max(0.05 * force, 0.5)
            self.assertAlmostEqual(-ft300[2], force, delta=tolerance, msg=seen[-1])
            self.assertAlmostEqual(contact[2], force, delta=tolerance, msg=seen[-1])
            self.assertAlmostEqual(robot[2], ft300[2], delta=1.0, msg=seen[-1])
        say('force_mode: ' + '; '.join(seen))

    def test_2_compliant_in_x_and_y_the_tool_does_not_drift(self):
        self.press.start(*force_mode_press.START_XY)
        self.press.script.run('def drift():\n'
                              '  force_mode(get_actual_tcp_pose(), [1, 1, 1, 0, 0, 0], [0, 0, 20, 0, 0, 0], 2, '
                              '[0.1, 0.1, 0.05, 0.17, 0.17, 0.17])\n'
                              '  sleep(5)\n  end_force_mode()\n'
                              '  movel(pose_trans(get_actual_tcp_pose(), p[0, 0, -0.02, 0, 0, 0]), a=0.5, v=0.05)\n'
                              'end\n')
        rospy.sleep(3.0)
        before = self.tool_position()
        rospy.sleep(1.0)
        after = self.tool_position()
        drift = np.linalg.norm((after - before)[:2])
        say('x/y compliant: %.3f mm/s' % (1e3 * drift))
        self.assertLess(drift, 0.001)
        rostest_helpers.wait_for(lambda: self.press.script.program_running is False, 'the program', 60)
        rospy.sleep(2.5)
        self.press.script.resume()

    def test_3_movel_keeps_the_tool_on_its_line(self):
        self.press.start(*force_mode_press.START_XY)
        start = self.tool_position()
        path = []
        recorder = rospy.Subscriber('joint_states', rospy.AnyMsg, lambda msg: path.append(self.tool_position()))
        self.press.script.run('def line():\n'
                              '  movel(pose_add(get_actual_tcp_pose(), p[0.1, -0.08, 0.05, 0, 0, 0]), a=1.2, v=0.25)\n'
                              'end\n')
        # The flange (tool0) moves along the line; gripper_tcp is rigidly below it with the same orientation.
        # pose_add moves the TCP in the robot's base frame, which is base_link turned half a turn about z.
        target = start + np.array([-0.1, 0.08, 0.05])
        # The program runs when the robot has compiled it, which a busy machine delays by seconds of the
        # cell's time at factor 0 (robot_program_running already reads false once it was sent): the tool's
        # arrival is waited for (and the distance that remains is the timeout's message).
        rostest_helpers.wait_for(lambda: np.linalg.norm(self.tool_position() - target) < 0.0005,
                                 lambda: 'the tool at the movel\'s target (%.3f mm away)'
                                 % (1e3 * np.linalg.norm(self.tool_position() - target)), 60)
        rospy.sleep(1.0)  # and it stays there
        recorder.unregister()
        end = self.tool_position()
        unit = (target - start) / np.linalg.norm(target - start)
        off_line = max(np.linalg.norm((p - start) - unit * np.dot(p - start, unit)) for p in path)
        say('movel: %.3f mm off the line at most, ends %.3f mm from the target' % (
            1e3 * off_line, 1e3 * np.linalg.norm(end - target)))
        self.assertLess(off_line, 0.001)
        self.assertLess(np.linalg.norm(end - target), 0.0005)
        self.press.script.resume()

    def test_4_a_program_that_does_not_compile_is_refused_naming_its_line(self):
        since = time.monotonic()
        self.press.script.publisher.publish('def broken():\n  x = 1\n  movel(p[0.1, 0.2, 0.3, 0, 0, 0]\nend\n')
        text = rostest_helpers.wait_for_log(self.rosout, '/ur_hardware_interface', Log.ERROR, 'would not compile',
                                            since=since)[0]
        say(text)
        self.assertIn('line 4', text)
        self.assertTrue(self.press.script.program_running)

    def test_5_the_example_runs_as_a_user_runs_it(self):
        # Its own main, through rosrun, on the same cell: what the README shows.
        force = 15.0
        done = subprocess.run(['rosrun', 'ur3_ft_gripper_description', 'force_mode_press.py', '--forces', str(force)],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=300)
        say(done.stdout.strip().splitlines()[-1] if done.stdout.strip() else '(no output)')
        self.assertEqual(done.returncode, 0, done.stdout)
        line = re.search(r'force_mode +([-\d.]+) N: FT 300 fz +([-\d.]+) N, robot wrench fz +([-\d.]+) N',
                         done.stdout)
        self.assertIsNotNone(line, done.stdout)
        asked, ft300, robot = (float(v) for v in line.groups())
        self.assertEqual(asked, force)
        self.assertAlmostEqual(-ft300, force, delta=max(0.05 * force, 0.5), msg=line.group(0))
        self.assertAlmostEqual(robot, ft300, delta=1.0, msg=line.group(0))


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'urscript_physics', UrscriptPhysicsTest)
