"""What test/physics shares: the start pose, the table, and ways to drive a physics Cell as the nodes do.

Fixtures (the exported robot, make_cell, between_pads) stay in test/physics/conftest.py.
"""
import math
import threading
import time

import numpy as np

from ur3_ft_gripper_description.devices.physics.link import CellServer
from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics
from ur3_ft_gripper_description.devices.ur_arm.joints import JointCommand
from ur3_ft_gripper_description.devices.ur_arm.physics_joints import PhysicsJointMotion

# The simulated arm's start pose (devices/ur_arm/settings.py): elbow bent, tool pointing down.
# The 2F-140's pads then hang over the table with their lower edges 60 mm above its top (z = 0).
START = np.array([0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0])
ARM_JOINTS = ('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint',
              'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint')
STANDARD_GRAVITY = 9.80665
TABLE = """
table:
  size: [1.0, 1.2, 0.04]
  pose: [0.2, 0.0, -0.02]
  friction: 0.5
"""


def in_gripper(cell, name):
    """Position (m) of object `name` in the 2F-140's base frame: what moves when it slips."""
    base, rotation = cell.body_pose(cell.gripper_base)
    return rotation.T.dot(cell.object_pose(name)[0] - base)


class Arm(object):
    """The joint-motion interface over a cell, and Cartesian moves of tool0 through the model's IK."""

    def __init__(self, cell):
        self.cell = cell
        self.motion = PhysicsJointMotion(cell)
        self.kinematics = ArmKinematics(cell.urdf_text, cell.arm_joints, 'base', 'tool0')

    def hold(self, seconds, dt=0.002):
        for _ in range(int(round(seconds / dt))):
            self.motion.step(JointCommand('HOLD'), dt)

    def move_tool(self, offset, duration, dt=0.002, until=None):
        """Move tool0 by `offset` (m, in the robot's base frame) along a line, smoothly; stop early if until()."""
        seed = self.motion.reference.copy()
        start = self.kinematics.forward(seed)
        steps = int(round(duration / dt))
        for k in range(1, steps + 1):
            s = k / float(steps)
            target = start.copy()
            target[:3, 3] += np.asarray(offset) * (0.5 - 0.5 * math.cos(math.pi * s))
            seed = self.kinematics.inverse(target, seed, tolerance=1e-10)  # smooth: no IK jitter
            assert seed is not None, 'the line leaves the arm\'s reach'
            self.motion.step(JointCommand('MOVE', seed), dt)
            if until is not None and until():
                return True
        return False

    def move_joints(self, delta, duration, dt=0.002):
        """Move the joints by `delta` (rad) along a quintic in `duration` s (MOVE, velocity fed)."""
        start = self.motion.reference.copy()
        delta = np.asarray(delta, dtype=float)
        steps = int(round(duration / dt))
        for k in range(1, steps + 1):
            s = k / float(steps)
            blend = 10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5
            rate = (30 * s ** 2 - 60 * s ** 3 + 30 * s ** 4) / duration
            self.motion.step(JointCommand('MOVE', start + delta * blend, delta * rate), dt)
            yield k * dt


def close_on(cell, force, speed=0.1, seconds=2.0):
    """Close the fingers fully at `speed` (m/s) with `force` (N); return the FingerState once stopped."""
    cell.command_finger(0.0, speed, force)
    for _ in range(int(round(seconds / 0.01))):
        cell.step(0.01)
        state = cell.finger()
        if state.motion != 'moving':
            return state
    return cell.finger()


class Served(object):
    """`cell` served at `path` (link.CellServer), stepped by a thread as the arm's node steps it; close() ends both."""

    def __init__(self, cell, path, authkey=None, period=0.008):
        self.cell = cell
        self.server = CellServer(cell, path, authkey=authkey)
        self._running = True

        def arm_loop():
            while self._running:
                with self.server.lock:
                    cell.step(period)
                time.sleep(0.001)
        self._thread = threading.Thread(target=arm_loop, daemon=True)
        self._thread.start()

    def close(self):
        self._running = False
        self._thread.join()
        self.server.close()
