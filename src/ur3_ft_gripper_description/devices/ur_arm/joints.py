"""The one seam between what the simulated UR controller commands and how the arm's joints move.

Every control cycle the arm's core (core.ArmCore) produces one JointCommand
and hands it to the joints object it was given, which moves the joints by
one period. The core never asks which implementation it has. An
implementation offers:

- `position`, `velocity`, `effort`: the joints' state, six floats each
  (numpy arrays, controller order: shoulder_pan ... wrist_3; rad, rad/s, Nm);
- `step(command, dt)`: move the joints for `dt` seconds under `command`;
- `flange_wrench`: what the tool exerts on the flange (six floats: N, N m in
  tool0's axes, about its origin), or None where nothing is measured; the
  robot's own TCP wrench starts from it (tcp_wrench.py);
- `protective_stop`: None, or a one-line reason when the last step() made the
  robot stop as a real UR does (a collision, a joint or force limit). Each
  step() sets it anew; the core latches the stop itself (safety mode
  PROTECTIVE_STOP) until `unlock protective stop`, and meanwhile commands HOLD.

Command modes, what a real UR does for each:
- HOLD: stand still (brakes released, holding); `position` is where the arm
  was when it began to hold. Until a controller commands, the arm holds its
  start pose.
- SERVO: streamed positions through servoj, which smooths them with its
  lookahead time (the trajectory and Cartesian controllers); `position` the
  target of this cycle, `velocity` the trajectory's own velocity (may be None).
- MOVE: the robot's own exact interpolation (a movej of URScript; the
  twist controller's speedl target): `position` is where the joints are to be
  at the end of this cycle.
- VELOCITY: speedj (joint_group_vel_controller): `velocity` the joint speeds.

KinematicJoints, the first implementation, is kinematic: the joints go where
they are commanded, no faster than the model's velocity limits and never
beyond its position limits; no dynamics, no collisions, so it never reports
a protective stop; nothing touches the tool, so it measures no flange wrench.
"""

import math

import numpy as np

HOLD, SERVO, MOVE, VELOCITY = 'HOLD', 'SERVO', 'MOVE', 'VELOCITY'
MODES = (HOLD, SERVO, MOVE, VELOCITY)


class JointCommand(object):
    """One cycle's command: a mode of MODES, and the position and/or velocity it needs (six floats)."""

    __slots__ = ('mode', 'position', 'velocity')

    def __init__(self, mode, position=None, velocity=None):
        if mode not in MODES:
            raise ValueError('joint command mode %r: use one of %s' % (mode, ', '.join(MODES)))
        self.mode = mode
        self.position = position
        self.velocity = velocity

    def __repr__(self):
        return 'JointCommand(%s, position=%s, velocity=%s)' % (self.mode, self.position, self.velocity)


class KinematicJoints(object):
    """Joints that follow their commands kinematically (servoj's smoothing as a first-order lag).

    ur_robot_driver streams the controllers' joint positions to the robot's
    servoj, whose `lookahead_time` (ur_control.launch's servoj_lookahead_time,
    0.03 s by default) "smoothens the trajectory with this lookahead time"
    (URScript manual): SERVO follows its position as a first-order lag with
    that time constant. So the arm ends a motion a few hundredths of a second
    after its command, as the real one does, and a trajectory asked to stop
    within a goal time shorter than that fails its goal tolerance
    (ur_robot_driver's own integration test expects this). MOVE and VELOCITY
    are the robot's own interpolation and are followed exactly.
    """

    def __init__(self, initial, lower, upper, velocity_limits, servo_lag):
        self.position = np.array(initial, dtype=float)
        self.velocity = np.zeros_like(self.position)
        self.effort = np.zeros_like(self.position)
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.velocity_limits = np.asarray(velocity_limits, dtype=float)
        self.servo_lag = float(servo_lag)
        self.protective_stop = None
        self.flange_wrench = None
        self.stiffness = None  # rigid: no servo gives
        self.servo_damping = None  # nor damps

    @classmethod
    def from_settings(cls, settings):
        """At the start pose, within the model's limits, with servoj's lookahead time (settings.read_settings)."""
        arm = settings.arm
        return cls(settings.initial, arm.lower, arm.upper, arm.velocity, settings.servo_lag)

    def step(self, command, dt):
        if dt <= 0.0:
            self.velocity = np.zeros_like(self.position)
            return
        if command.mode == HOLD:
            target, lag = self.position, 0.0
        elif command.mode == VELOCITY:
            target, lag = self.position + np.asarray(command.velocity, dtype=float) * dt, 0.0
        else:
            target = command.position
            lag = self.servo_lag if command.mode == SERVO else 0.0
        self.position, self.velocity = follow(self.position, target, dt, lag, self.velocity_limits,
                                              self.lower, self.upper)


def follow(position, target, dt, lag, velocity_limits, lower, upper):
    """(position, velocity) of joints at `position` after following `target` for dt > 0 seconds."""
    position = np.asarray(position, dtype=float)
    # The lag's exact solution over dt, not an Euler step: the same motion whether a late cycle brings one
    # long dt or a punctual one several short ones (an Euler step past dt = lag jumps to the target, and
    # the velocity then swings from cycle to cycle, which kicks the physics servos).
    share = 1.0 if lag <= 0.0 else -math.expm1(-dt / lag)
    step = (np.asarray(target, dtype=float) - position) * share
    reach = np.asarray(velocity_limits, dtype=float) * dt
    # np.minimum / np.maximum rather than np.clip: a tenth of its cost per call on numpy 1.24, at 500 calls a second.
    moved = np.minimum(np.maximum(position + np.minimum(np.maximum(step, -reach), reach), lower), upper)
    return moved, (moved - position) / dt
