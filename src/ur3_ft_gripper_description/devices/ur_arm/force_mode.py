"""URScript's force_mode as the simulated controller runs it: no ROS.

`force_mode(task_frame, selection_vector, wrench, type, limits)` makes the
robot compliant along and about the selected axes of a force frame: there
it moves so as to apply `wrench` to the world, no faster than `limits`
(m/s, rad/s). Along the other axes it keeps to its program (here: where it
was, or the move the program runs). The frame comes from `task_frame` and
`type`, as the URScript manual defines them:

- 1: turned about its z so that its y axis points from the TCP towards
  the task frame's origin (a point the tool presses towards or pulls from);
- 2: the task frame as given;
- 3: turned about its z so that its x axis is the TCP's velocity projected
  on the task frame's x-y plane (a motion along a surface).

The law on each compliant axis is an admittance driven by the force error,
the commanded wrench minus the wrench the robot applies (minus its own
external TCP wrench, ``tcp_wrench``): a virtual mass accelerates along the
axis, and `force_mode_set_damping` (0 to 1, default 0.005) brakes it,
from no braking at 0 to losing a fraction of its speed each cycle at 1, as
the manual describes: without a force the robot keeps its speed at 0 and
decelerates quickly at 1. `force_mode_set_gain_scaling` (0 to 2, default 1)
scales the force error. In free air the robot thus accelerates to the speed
limit, as URSim does; in contact it settles where the world pushes back with
the commanded wrench. The virtual mass is chosen so that the tool settles
on the physics cell's stiffest contacts without bouncing at either control
period (bench/force_mode.py measures it).

Nothing here moves the arm: `step` gives the displacement of the TCP for one
control cycle, which the core adds to what the program commands.
"""

import math

import numpy as np

from .arm_kinematics import rotation_matrix

# The admittance's virtual mass (kg) and moment of inertia (kg m^2).
VIRTUAL_MASS = 10.0
VIRTUAL_INERTIA = 0.05
# At damping 1 the speed loses this fraction per second (the manual's "decelerates quickly").
FULL_DAMPING_RATE = 125.0
DEFAULT_DAMPING = 0.005
DEFAULT_GAIN_SCALING = 1.0
FRAME_TYPES = (1, 2, 3)


class ForceModeError(ValueError):
    """Arguments the robot refuses: one line, in the manual's terms."""


def _vector(values, length, name):
    try:
        vector = np.array([float(v) for v in values])
    except (TypeError, ValueError):
        raise ForceModeError('force_mode: %s must be a list of %d numbers' % (name, length)) from None
    if vector.shape != (length,) or not np.all(np.isfinite(vector)):
        raise ForceModeError('force_mode: %s must be a list of %d finite numbers' % (name, length))
    return vector


class ForceMode(object):
    """One force_mode call's settings and its state; `task_frame` a 4x4 in the robot's base frame."""

    def __init__(self, task_frame, selection_vector, wrench, frame_type, limits,
                 damping=DEFAULT_DAMPING, gain_scaling=DEFAULT_GAIN_SCALING):
        self.task_frame = np.asarray(task_frame, dtype=float)
        self.selection = _vector(selection_vector, 6, 'selection_vector') != 0.0
        self.wrench = _vector(wrench, 6, 'wrench')
        self.limits = np.abs(_vector(limits, 6, 'limits'))
        if frame_type not in FRAME_TYPES:
            raise ForceModeError('force_mode: type %r is not one of 1, 2, 3' % (frame_type,))
        self.frame_type = frame_type
        self.damping = min(max(float(damping), 0.0), 1.0)
        self.gain_scaling = min(max(float(gain_scaling), 0.0), 2.0)
        self.velocity = np.zeros(6)   # in the force frame: m/s, rad/s
        self.tcp_velocity = np.zeros(3)

    def force_frame(self, tcp_position):
        """The rotation (3x3, base axes) of the force frame, by `frame_type`."""
        rotation, origin = self.task_frame[:3, :3], self.task_frame[:3, 3]
        if self.frame_type == 2:
            return rotation
        z = rotation[:, 2]
        if self.frame_type == 1:
            towards = origin - np.asarray(tcp_position, dtype=float)
        else:
            towards = self.tcp_velocity
        towards = towards - z * towards.dot(z)   # onto the frame's x-y plane
        if np.linalg.norm(towards) < 1e-9:
            return rotation
        towards /= np.linalg.norm(towards)
        if self.frame_type == 1:
            y = towards
            x = np.cross(y, z)
        else:
            x = towards
            y = np.cross(z, x)
        return np.column_stack((x, y, z))

    def step(self, dt, tcp_position, external_wrench):
        """(linear, angular) displacement of the TCP in base axes over `dt` s.

        `external_wrench`: the robot's own TCP wrench in base axes (what the world exerts on the tool).
        """
        frame = self.force_frame(tcp_position)
        external = np.asarray(external_wrench, dtype=float)
        applied = -np.concatenate((frame.T.dot(external[:3]), frame.T.dot(external[3:])))
        error = self.gain_scaling * (self.wrench - applied)
        inertia = np.array([VIRTUAL_MASS] * 3 + [VIRTUAL_INERTIA] * 3)
        braking = math.exp(-FULL_DAMPING_RATE * self.damping * dt)
        velocity = self.velocity * braking + error / inertia * dt
        velocity = np.clip(velocity, -self.limits, self.limits)
        velocity[~self.selection] = 0.0
        self.velocity = velocity
        linear, angular = frame.dot(velocity[:3]) * dt, frame.dot(velocity[3:]) * dt
        self.tcp_velocity = linear / dt if dt > 0 else np.zeros(3)
        return linear, angular


def displaced(pose, linear, angular):
    """`pose` (4x4) moved by a linear and an angular displacement (base axes, about its own origin)."""
    moved = np.array(pose, dtype=float)
    moved[:3, 3] += linear
    if np.any(angular):
        moved[:3, :3] = rotation_matrix(angular).dot(moved[:3, :3])
    return moved

