"""The arm's joint motion on physics: the simulated arm's joint-motion seam over a physics Cell.

The simulated arm's core (``devices/ur_arm/core.py``) decides what the joints
are asked to do and hands each cycle's ``joints.JointCommand`` to its
joint-motion object; ``joints.KinematicJoints`` moves the joints where they
are asked. This one turns the same commands into the servo reference of a
physics ``Cell``, whose joints then follow it with their dynamics, limits
and contacts:

* HOLD: the reference stays where it is (at start-up, the start pose);
* SERVO: streamed positions through servoj's lookahead, the first-order lag
  of ``joints.follow`` (the kinematic model's own law), within the joints'
  velocity and position limits;
* MOVE: the robot's own interpolation (movej, the twist controller): the
  reference goes to the position without lag, within the limits;
* VELOCITY: speedj, the reference moves at the velocity, within the limits.

``protective_stop`` is set anew by every ``step``: the reason when the robot's
contact force passed the cell's limit during that step, else None. The cell
then holds the arm where it stopped (the servos no longer press on), and this
object releases the cell's own hold at once: the core latches the stop
(safety mode PROTECTIVE_STOP) and commands HOLD until the dashboard's
``unlock protective stop``, as the real controller does.
"""

import numpy as np

from . import joints
from .joints import HOLD, MOVE, SERVO, VELOCITY


class PhysicsJointMotion(object):
    """The arm's joints of `cell`, moved by joint commands; `lookahead` is servoj's (s).

    The velocity limits are the model's unless given (rad/s, one per joint).
    """

    def __init__(self, cell, lookahead=0.03, velocity_limits=None):
        self.cell = cell
        self.lookahead = float(lookahead)
        self.velocity_limits = np.asarray(cell.arm_velocity_limits if velocity_limits is None
                                          else velocity_limits, dtype=float)
        self.lower, self.upper = cell.arm_lower, cell.arm_upper
        self.reference = cell.arm_position
        self._still = np.zeros(len(self.reference))
        self.protective_stop = None

    @classmethod
    def from_settings(cls, cell, settings):
        """With the arm's settings (settings.read_settings): servoj's lookahead, the model's velocity limits."""
        return cls(cell, settings.servo_lag, settings.arm.velocity)

    @property
    def position(self):
        return self.cell.arm_position

    @property
    def velocity(self):
        return self.cell.arm_velocity

    @property
    def effort(self):
        return self.cell.arm_effort

    @property
    def stiffness(self):
        """The position servos' stiffness (N m/rad, one per joint): how far each gives under a torque."""
        return self.cell.arm_stiffness

    @property
    def servo_damping(self):
        """The velocity servos' gains (N m s/rad, one per joint): the reference's speed they push towards."""
        return self.cell.arm_servo_damping

    @property
    def flange_wrench(self):
        return self.cell.flange_wrench()

    def step(self, command, dt):
        """Follow `command` for `dt` seconds; protective_stop says whether the robot stopped meanwhile."""
        mode = command.mode
        if mode == HOLD:
            velocity = self._still
        else:
            if mode == SERVO:
                target, lag = command.position, self.lookahead
            elif mode == MOVE:
                target, lag = command.position, 0.0
            elif mode == VELOCITY:
                target, lag = self.reference + np.asarray(command.velocity, dtype=float) * dt, 0.0
            else:
                raise ValueError('joint command mode %r: use one of %s' % (mode, ', '.join(joints.MODES)))
            if dt > 0.0:
                self.reference, velocity = joints.follow(self.reference, target, dt, lag, self.velocity_limits,
                                                         self.lower, self.upper)
            else:
                velocity = self._still
        self.cell.set_arm_reference(self.reference, velocity)
        self.cell.step(dt)
        self.protective_stop = self.cell.protective_stop
        if self.protective_stop is not None:
            # The cell holds the arm where it stopped: from here the reference starts, and the latch is the core's.
            self.cell.clear_protective_stop()
            self.reference = self.cell.arm_position
