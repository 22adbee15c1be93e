#!/usr/bin/env python3
"""rostest node: the physics cell under load does what it does on a quiet machine (physics_under_load.test).

The same measurements through the real interfaces, first on a quiet machine,
then with one busy process per core beside the cell: pick and weigh, the
grasp's gPO, the guarded touch and a force-controlled touch. On the
simulated clock the load slows the cell down; what the cell decides alone
does not change:

- the grasp's gPO is the quiet one within a count;
- the weighed mass is the world file's within 2 % both times;
- the guarded touch stops on the table without a protective stop, and the
  steady force the FT 300 reads is MuJoCo's contact force, both times;
- a touch the robot's own force control holds (examples/force_mode_press.py
  at 20 N) reads the same steady force on the FT 300 quiet and loaded,
  within 0.2 N.

What the guarded touch's figures do not repeat is how far it pressed: it
reacts to the readings on its own schedule, and the cell runs on meanwhile,
as a real cell does (doc/simulation.md: what is not deterministic). Its
steady force is printed for both runs, not compared. force_mode is decided
on the robot, in the cell's control cycles, so its touch must repeat.
"""
import os
import sys
import unittest

import rospkg
import rospy
import rostest

import numpy as np

from ur3_ft_gripper_description.devices.physics.world import load_world
from ur3_ft_gripper_testing import rostest_helpers, shipped
from ur3_ft_gripper_testing.cpu_load import CpuLoad

PACKAGE_DIR = rospkg.RosPack().get_path('ur3_ft_gripper_description')
WORLD = os.path.join(PACKAGE_DIR, 'test', 'data', 'worlds', 'grasp_matrix.yaml')
force_mode_press = shipped.script('examples/force_mode_press.py')
guarded_touch = shipped.script('examples/guarded_touch.py')
pick_and_weigh = shipped.script('examples/pick_and_weigh.py')

GPO_AGREEMENT = 1          # counts
# The guarded touch's speed (m/s): a tenth of the example's. The arm presses on until the stop arrives,
# and a busy machine delays it: at 150 N the robot stops itself, as it did once at 5 mm/s in CI, beside
# a second CI run and the test's own load. At 2 mm/s a delay takes the tool 2.5 times less far. It
# starts low, the open pads 19 mm over the table, so that the slow touch takes no longer, and backs
# off at the example's speed.
TOUCH_SPEED = 0.002
TOUCH_HEIGHT = 0.03        # gripper_tcp over the table (m)
BACK_OFF_SPEED = 0.02
WEIGHT_TOLERANCE = 0.02    # against the world file
# The steady force against MuJoCo's contact force, relative (as physics_cell.test).
CONTACT_TOLERANCE = 0.02
PRESS_FORCE = 20.0         # N, force_mode's along the tool
PRESS_AGREEMENT = 0.2      # N, quiet against loaded


def say(text):
    print('[physics_under_load] %s' % text)
    sys.stdout.flush()


class PhysicsUnderLoadTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('physics_under_load_check')
        cls.world = load_world(WORLD)
        cls.cell = pick_and_weigh.PickAndWeigh(rospy, say=say)
        cls.touch = guarded_touch.GuardedTouch(rospy, say=say)
        cls.press = force_mode_press.ForceModePress(rospy, say=say)
        cls.truth_link = rostest_helpers.cell_link()

    def measure(self):
        """(weighed mass kg, gPO on the block, the guarded touch's steady force N, MuJoCo's contact force N,
        the FT 300's force under force_mode N)."""
        x, y, top, yaw, width, mass = pick_and_weigh.target_of(WORLD, 'block')
        self.cell.pick(x, y, top, yaw)
        gpo = self.cell.gripper.status.gPO
        weighed = self.cell.weigh()[0]
        self.cell.put_down()
        self.touch.start(*guarded_touch.START_XY, height=TOUCH_HEIGHT)
        figures = self.touch.touch(TOUCH_SPEED, 10.0)
        contact = float(np.linalg.norm(self.truth_link.truth()[1]['contact_force']))
        self.touch.back_off(BACK_OFF_SPEED)
        self.press.start(*force_mode_press.START_XY)
        seconds = force_mode_press.SETTLE + force_mode_press.MEASURE
        pressed = -self.press.press(PRESS_FORCE, 0.05, seconds)['ft300_fz']
        return weighed, gpo, figures['steady_force'], contact, pressed

    def test_the_load_slows_the_cell_and_changes_none_of_its_figures(self):
        quiet = self.measure()
        say('quiet: %.4f kg, gPO %d, steady force %.3f N (MuJoCo: %.3f N), force_mode %.3f N' % quiet)
        with CpuLoad() as load:
            loaded = self.measure()
        say('with %d busy processes: %.4f kg, gPO %d, steady force %.3f N (MuJoCo: %.3f N), force_mode %.3f N'
            % ((load.count,) + loaded))
        mass = self.world.by_name('block').mass
        for figures in (quiet, loaded):
            weighed, _, steady, contact, pressed = figures
            self.assertAlmostEqual(weighed, mass, delta=WEIGHT_TOLERANCE * mass)
            self.assertGreater(steady, 0.5, 'the tool does not rest on the table')
            self.assertAlmostEqual(steady, contact, delta=CONTACT_TOLERANCE * contact + 0.02)
            self.assertAlmostEqual(pressed, PRESS_FORCE, delta=0.05 * PRESS_FORCE)
        self.assertLessEqual(abs(loaded[1] - quiet[1]), GPO_AGREEMENT, 'gPO on the block')
        self.assertAlmostEqual(loaded[4], quiet[4], delta=PRESS_AGREEMENT, msg='the force_mode touch (N)')


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'physics_under_load', PhysicsUnderLoadTest)
