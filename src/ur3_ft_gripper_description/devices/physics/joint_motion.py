"""The arm's joint motion on physics: the simulated arm's joint-motion interface over a Cell.

The simulated arm's core decides what the joints are asked to do; an
implementation of its joint-motion interface makes them do it. The kinematic
one moves them where they are asked (``devices/ur_arm/joints.py``); this one
turns the same commands into the servo reference of a physics ``Cell``,
whose joints then follow it with their dynamics, limits and contacts:

* HOLD: the reference stays where it is (at start-up, the start pose);
* SERVO: streamed positions through servoj's lookahead, the first-order lag
  of ``joints.follow`` (the kinematic model's own law), within the joints'
  velocity and position limits;
* MOVE: the robot's own interpolation (movej, a trajectory the controller
  executes exactly): the reference goes to the position without lag, within
  the limits;
* VELOCITY: speedj, the reference moves at the velocity, within the limits.

Interface: ``position``, ``velocity``, ``effort`` (one value per arm joint),
``step(command, dt)``, ``protective_stop`` (None, or why the arm stopped;
it holds the arm until ``clear_protective_stop()``).

``JointCommand`` here is a stand-in for the arm core's command type: any
object with ``mode`` (one of the four names) and ``position`` / ``velocity``
(sequences, or None where the mode needs none) will do.
"""

import numpy as np

from ..ur_arm import joints

HOLD, SERVO, MOVE, VELOCITY = 'HOLD', 'SERVO', 'MOVE', 'VELOCITY'
MODES = (HOLD, SERVO, MOVE, VELOCITY)


class JointCommand(object):
    """What the arm's joints are asked to do: a mode and its positions or velocities (rad, rad/s)."""

    def __init__(self, mode, position=None, velocity=None):
        if mode not in MODES:
            raise ValueError('joint command mode %r: use one of %s' % (mode, ', '.join(MODES)))
        self.mode, self.position, self.velocity = mode, position, velocity


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
    def protective_stop(self):
        return self.cell.protective_stop

    def clear_protective_stop(self):
        self.cell.clear_protective_stop()
        self.reference = self.cell.arm_position

    def step(self, command, dt):
        """Follow `command` for `dt` seconds."""
        if self.cell.protective_stop is not None:
            self.reference = self.cell.arm_position
            self.cell.step(dt)
            return
        mode = command.mode
        if mode == HOLD:
            self.cell.set_arm_reference(self.reference, self._still)
            self.cell.step(dt)
            return
        if mode == SERVO:
            target, lag = command.position, self.lookahead
        elif mode == MOVE:
            target, lag = command.position, 0.0
        elif mode == VELOCITY:
            target, lag = self.reference + np.asarray(command.velocity, dtype=float) * dt, 0.0
        else:
            raise ValueError('joint command mode %r: use one of %s' % (mode, ', '.join(MODES)))
        if dt > 0.0:
            self.reference, velocity = joints.follow(self.reference, target, dt, lag, self.velocity_limits,
                                                     self.lower, self.upper)
        else:
            velocity = np.zeros(len(self.reference))
        self.cell.set_arm_reference(self.reference, velocity)
        self.cell.step(dt)
        if self.cell.protective_stop is not None:
            self.reference = self.cell.arm_position
