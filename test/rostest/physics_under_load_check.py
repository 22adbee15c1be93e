#!/usr/bin/env python3
"""rostest node: the physics cell's figures do not change with the machine's load (physics_under_load.test).

The same three measurements through the real interfaces, first on a quiet
machine, then with one busy process per core beside the cell: the mass
pick and weigh reads from the FT 300, the gPO the 2F-140 reports on the
grasped block, and the steady force the guarded touch reads standing on the
table. On the simulated clock the load can only slow the cell down: each
loaded figure is the quiet one within 0.2 %, 1 count and 0.2 N, and the
mass is the world file's within 2 % both times.
"""
import os
import sys
import unittest

import rospkg
import rospy
import rostest

from ur3_ft_gripper_description.devices.physics.world import load_world
from ur3_ft_gripper_testing import shipped
from ur3_ft_gripper_testing.cpu_load import CpuLoad

PACKAGE_DIR = rospkg.RosPack().get_path('ur3_ft_gripper_description')
WORLD = os.path.join(PACKAGE_DIR, 'test', 'data', 'worlds', 'grasp_matrix.yaml')
guarded_touch = shipped.script('examples/guarded_touch.py')
pick_and_weigh = shipped.script('examples/pick_and_weigh.py')

MASS_AGREEMENT = 0.002     # relative
GPO_AGREEMENT = 1          # counts
FORCE_AGREEMENT = 0.2      # N
WEIGHT_TOLERANCE = 0.02    # against the world file


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

    def measure(self):
        """(weighed mass kg, gPO on the block, the guarded touch's steady force N)."""
        x, y, top, yaw, width, mass = pick_and_weigh.target_of(WORLD, 'block')
        self.cell.pick(x, y, top, yaw)
        gpo = self.cell.gripper.status.gPO
        weighed = self.cell.weigh()[0]
        self.cell.put_down()
        self.touch.start(*guarded_touch.START_XY)
        figures = self.touch.touch(0.02, 10.0)
        self.touch.back_off(0.02)
        return weighed, gpo, figures['steady_force']

    def test_the_load_slows_the_cell_and_changes_none_of_its_figures(self):
        quiet = self.measure()
        say('quiet: %.4f kg, gPO %d, steady force %.3f N' % quiet)
        with CpuLoad() as load:
            loaded = self.measure()
        say('with %d busy processes: %.4f kg, gPO %d, steady force %.3f N' % ((load.count,) + loaded))
        mass = self.world.by_name('block').mass
        for weighed in (quiet[0], loaded[0]):
            self.assertAlmostEqual(weighed, mass, delta=WEIGHT_TOLERANCE * mass)
        self.assertAlmostEqual(loaded[0], quiet[0], delta=MASS_AGREEMENT * quiet[0], msg='weighed mass (kg)')
        self.assertLessEqual(abs(loaded[1] - quiet[1]), GPO_AGREEMENT, 'gPO on the block')
        self.assertAlmostEqual(loaded[2], quiet[2], delta=FORCE_AGREEMENT, msg='steady force (N)')


if __name__ == '__main__':
    rostest.rosrun('ur3_ft_gripper_description', 'physics_under_load', PhysicsUnderLoadTest)
