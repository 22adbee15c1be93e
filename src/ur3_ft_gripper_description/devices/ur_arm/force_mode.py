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
period (test/physics/test_force_mode.py settles it at both).

Nothing here moves the arm: `step` gives the displacement of the TCP for one
control cycle, which the core adds to what the program commands.

On joint servos that give (the physics cell's), a displaced pose alone is
not what the robot does. Where the tool is held (pressed on a table), the
target runs ahead of the TCP, and the servos pull towards it with their
Cartesian stiffness J^-T K J^-1; with a stiffness per joint that couples
the axes, so a lead straight down pulls across as well. `uncoupled` moves
the target's non-compliant axes just enough to cancel that pull: the
robot then pushes along the compliant axes only, as the force it
controls, and holds the others where the program wants them. The lead
is counted from where the admittance's own motion takes the TCP, so in
free air, where the TCP keeps up, the target is the displaced pose alone.

Those servos also damp: the commanded speed is fed forward, and where the
tool is held, a change of it comes back within the cycle as the servos'
damping force (their velocity gains at the TCP, J^-T Kv J^-1). Against
that force the admittance is integrated implicitly (the virtual mass
plus that damping times the period): explicitly, the loop's gain per
cycle is C dt / M, which reaches 2 at the CB3's 8 ms on a pressed tool,
and the force then rings at half the control rate instead of settling.
"""

import math

import numpy as np

from .arm_kinematics import pose_error, rotation_matrix

# The admittance's virtual mass (kg) and moment of inertia (kg m^2).
VIRTUAL_MASS = 10.0
VIRTUAL_INERTIA = 0.05
INERTIA = (VIRTUAL_MASS,) * 3 + (VIRTUAL_INERTIA,) * 3
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
        self.frame = self.task_frame[:3, :3]  # the force frame of the last step (3x3, base axes)

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

    def step(self, dt, tcp_position, external_wrench, servo_damping=None):
        """(linear, angular) displacement of the TCP in base axes over `dt` s.

        `external_wrench`: the robot's own TCP wrench in base axes (what the world exerts on the tool).
        `servo_damping`: on joint servos that give, their damping at the TCP (6x6, base axes:
        servos_at_tcp of their velocity gains), which the admittance is integrated against.
        """
        frame = self.frame = self.force_frame(tcp_position)
        external = np.asarray(external_wrench, dtype=float)
        applied = -_in_frame(frame, external)
        error = self.gain_scaling * (self.wrench - applied)
        braking = math.exp(-FULL_DAMPING_RATE * self.damping * dt)
        inertia = np.array(INERTIA)
        if servo_damping is not None:
            inertia += self._servo_inertia(frame, servo_damping) * dt
        velocity = self.velocity * braking + error / inertia * dt
        velocity = np.clip(velocity, -self.limits, self.limits)
        velocity[~self.selection] = 0.0
        self.velocity = velocity
        linear, angular = frame.dot(velocity[:3]) * dt, frame.dot(velocity[3:]) * dt
        self.tcp_velocity = linear / dt if dt > 0 else np.zeros(3)
        return linear, angular

    def _servo_inertia(self, frame, servo_damping):
        """Per axis of the force frame, the servos' damping the admittance meets there (N s/m, N m s/rad):
        on the linear and on the angular compliant axes alike, the strongest of that block (its largest
        eigenvalue), so that the loop stays below one per cycle along any direction, and no axis steers
        another (in free air the tool keeps up and the servos' damping does not push)."""
        rotation = _rotation6(frame)
        damping = rotation.T.dot(servo_damping).dot(rotation)
        per_axis = np.zeros(6)
        for block in (slice(0, 3), slice(3, 6)):
            chosen = np.flatnonzero(self.selection[block]) + block.start
            if len(chosen):
                per_axis[chosen] = np.linalg.eigvalsh(damping[np.ix_(chosen, chosen)])[-1]
        return per_axis


def displaced(pose, linear, angular):
    """`pose` (4x4) moved by a linear and an angular displacement (base axes, about its own origin)."""
    moved = np.array(pose, dtype=float)
    moved[:3, 3] += linear
    if np.any(angular):
        moved[:3, :3] = rotation_matrix(angular).dot(moved[:3, :3])
    return moved


def _rotation6(frame):
    """The 6x6 that turns a (linear, angular) 6-vector of `frame`'s axes (3x3) into base axes."""
    rotation = np.zeros((6, 6))
    rotation[:3, :3] = rotation[3:, 3:] = frame
    return rotation


def servos_at_tcp(jacobian, gains):
    """Joint servos' gains (one per joint: N m/rad, or N m s/rad) as the TCP meets them: J^-T diag(gains) J^-1
    (6x6, base axes), the wrench per displacement (or per speed) of the TCP. `jacobian`: the TCP's 6xN
    geometric Jacobian (base axes)."""
    inverse = np.linalg.inv(jacobian)  # joint offsets per displacement of the TCP
    return inverse.T.dot(inverse * np.asarray(gains, dtype=float)[:, None])


def _in_frame(frame, six):
    """A 6-vector (linear, angular) of base axes in the axes of `frame` (3x3), or back with frame.T."""
    return np.concatenate((frame.T.dot(six[:3]), frame.T.dot(six[3:])))


def lead(frame, selection, pose, actual):
    """How far `pose` is ahead of `actual` (4x4 TCP poses) along the compliant axes: a 6-vector in the
    force frame's axes (m, rad), zero on the other axes."""
    ahead = _in_frame(frame, pose_error(pose, actual))
    ahead[~selection] = 0.0
    return ahead


def back(frame, ahead):
    """(linear, angular) displacement in base axes that takes a pose back by `ahead` (lead()): moved by
    it (displaced()), the pose is where the TCP is along the compliant axes."""
    behind = -_in_frame(frame.T, ahead)
    return behind[:3], behind[3:]


def uncoupled(jacobian, stiffness, frame, selection, ahead):
    """(linear, angular) displacement in base axes of the target's non-compliant axes that cancels their
    pull from the compliant axes' lead.

    Joint servos of `stiffness` (N m/rad, one per joint) pulling towards a target `ahead` (lead()) of
    the TCP pull with K J^-1 (the Cartesian stiffness J^-T K J^-1 times the lead); that stiffness
    couples the axes, so a lead along z pulls across too. Moved by this, the target pulls along the
    compliant axes alone, as hard as the servos' stiffness there with the other axes held.
    `jacobian`: the TCP's 6xN geometric Jacobian (base axes).
    """
    held, pushed = np.flatnonzero(~selection), np.flatnonzero(selection)
    if not len(held) or not len(pushed):
        return np.zeros(3), np.zeros(3)
    rotation = _rotation6(frame)
    cartesian = rotation.T.dot(servos_at_tcp(jacobian, stiffness)).dot(rotation)  # the servos' stiffness, force frame
    shift = np.zeros(6)
    shift[held] = -np.linalg.solve(cartesian[held][:, held], cartesian[held][:, pushed].dot(ahead[pushed]))
    base = rotation.dot(shift)
    return base[:3], base[3:]
