"""Joint trajectories as ros_controllers' joint_trajectory_controller runs them, without ROS.

What a FollowJointTrajectory goal means, taken from the controller's
documentation (wiki.ros.org/joint_trajectory_controller) and the action
definition:
- the goal names every joint of the controller, in any order; an unknown,
  missing or repeated name is INVALID_JOINTS;
- every point has one position per joint, velocities and accelerations
  either empty or one per joint, times strictly increasing: else INVALID_GOAL;
- the motion starts from the current state at the goal's header.stamp (zero:
  now) and goes through the points by splines: linear where a point has
  positions only, cubic with velocities, quintic with accelerations;
- tolerances: the controller's `constraints` (trajectory = path position,
  goal = goal position, stopped_velocity_tolerance = goal velocity,
  goal_time), overridden per joint by the goal (> 0 replaces, -1 switches the
  check off, 0 keeps the default);
- a cancelled goal stops within stop_trajectory_duration.

The simulation refuses a point that is NaN or beyond the model's joint
limits with INVALID_GOAL (the real robot would stop with a fault); the
names of the result codes are those of control_msgs/FollowJointTrajectoryResult,
which the node maps to the message's values.
"""

import collections
import math

import numpy as np

# A goal's per-joint tolerance (control_msgs/JointTolerance in plain numbers).
JointTolerance = collections.namedtuple('JointTolerance', 'name position velocity acceleration')


class GoalError(ValueError):
    """A goal the controller refuses: `code` names a FollowJointTrajectoryResult constant."""

    def __init__(self, code, message):
        super(GoalError, self).__init__(message)
        self.code = code


def order_joints(controller_joints, goal_joints):
    """Index into the goal's columns for each controller joint, or GoalError INVALID_JOINTS."""
    unknown = [name for name in goal_joints if name not in controller_joints]
    if unknown:
        raise GoalError('INVALID_JOINTS', 'Unknown joint(s) %s: this controller has %s'
                        % (', '.join(unknown), ', '.join(controller_joints)))
    if len(set(goal_joints)) != len(goal_joints):
        raise GoalError('INVALID_JOINTS', 'Joint names %s repeat a joint' % ', '.join(goal_joints))
    missing = [name for name in controller_joints if name not in goal_joints]
    if missing:
        raise GoalError('INVALID_JOINTS', 'Joints on incoming goal don\'t match the controller joints: '
                        'missing %s' % ', '.join(missing))
    return [list(goal_joints).index(name) for name in controller_joints]


class Point(object):
    """One trajectory point in plain numbers: seconds from the start, and per-joint lists."""

    def __init__(self, time, positions, velocities=(), accelerations=()):
        self.time = float(time)
        self.positions = list(positions)
        self.velocities = list(velocities)
        self.accelerations = list(accelerations)


def validate_points(controller_joints, goal_joints, points, lower, upper):
    """The points in the controller's joint order as arrays (times, pos, vel|None, acc|None).

    `lower`/`upper`: the joints' position limits in the controller's order.
    Raises GoalError (INVALID_JOINTS / INVALID_GOAL) with one line naming the problem.
    """
    columns = order_joints(controller_joints, goal_joints)
    n = len(goal_joints)
    if not points:
        raise GoalError('INVALID_GOAL', 'The trajectory has no points')
    times = []
    for index, point in enumerate(points):
        if len(point.positions) != n:
            raise GoalError('INVALID_GOAL', 'Point %d has %d positions for %d joints'
                            % (index, len(point.positions), n))
        for field in ('velocities', 'accelerations'):
            size = len(getattr(point, field))
            if size not in (0, n):
                raise GoalError('INVALID_GOAL', 'Point %d has %d %s for %d joints (give none or one per joint)'
                                % (index, size, field, n))
        values = point.positions + point.velocities + point.accelerations + [point.time]
        if not all(math.isfinite(v) for v in values):
            raise GoalError('INVALID_GOAL', 'Point %d holds a NaN or infinite value' % index)
        if point.time < 0.0:
            raise GoalError('INVALID_GOAL', 'Point %d has a negative time_from_start (%g s)' % (index, point.time))
        if times and point.time <= times[-1]:
            raise GoalError('INVALID_GOAL', 'Trajectory message contains waypoints that are not strictly '
                            'increasing in time: point %d at %g s after %g s' % (index, point.time, times[-1]))
        times.append(point.time)

    def field(name):
        rows = [getattr(p, name) for p in points]
        if any(len(r) == 0 for r in rows):
            return None
        return np.asarray(rows, dtype=float)[:, columns]

    positions = field('positions')
    for j, name in enumerate(controller_joints):
        column = positions[:, j]
        bad = np.nonzero((column < lower[j]) | (column > upper[j]))[0]
        if bad.size:
            raise GoalError('INVALID_GOAL', 'Point %d puts %s at %.4f rad, beyond its limits [%.4f, %.4f]'
                            % (bad[0], name, column[bad[0]], lower[j], upper[j]))
    return np.asarray(times), positions, field('velocities'), field('accelerations')


class Spline(object):
    """Piecewise polynomial through states (t, p, v, a) per joint, as joint_trajectory_controller builds it.

    Segment i goes from state i to state i+1; its kind follows the data of
    its end point: positions only -> linear, with velocities -> cubic, with
    accelerations -> quintic. Before the first time it holds the first
    state, after the last it holds the last position.
    """

    def __init__(self, times, positions, velocities=None, accelerations=None):
        self.times = np.asarray(times, dtype=float)
        self.positions = np.asarray(positions, dtype=float)
        n_points, n_joints = self.positions.shape
        zeros = np.zeros((n_points, n_joints))
        self.kind = 'linear' if velocities is None else ('cubic' if accelerations is None else 'quintic')
        self.velocities = zeros if velocities is None else np.asarray(velocities, dtype=float)
        self.accelerations = zeros if accelerations is None else np.asarray(accelerations, dtype=float)
        self.coefficients = [self._segment(i) for i in range(n_points - 1)]
        # Those of the velocity and the acceleration, made once: a controller samples every cycle.
        self.velocity_coefficients = [c[1:] * np.arange(1, 6)[:, None] for c in self.coefficients]
        self.acceleration_coefficients = [c[2:] * (np.arange(2, 6) * np.arange(1, 5))[:, None]
                                          for c in self.coefficients]
        self._last = None  # (t, its sample): a cycle asks for the same time more than once

    @property
    def end_time(self):
        return float(self.times[-1])

    def _segment(self, i):
        """Polynomial coefficients c[k] (k = 0..5, per joint) of p(s) = sum c[k] s^k, s from segment start."""
        T = self.times[i + 1] - self.times[i]
        p0, p1 = self.positions[i], self.positions[i + 1]
        v0, v1 = self.velocities[i], self.velocities[i + 1]
        a0, a1 = self.accelerations[i], self.accelerations[i + 1]
        c = np.zeros((6, p0.size))
        c[0] = p0
        if self.kind == 'linear':
            c[1] = (p1 - p0) / T
        elif self.kind == 'cubic':
            c[1] = v0
            c[2] = (3.0 * (p1 - p0) - (2.0 * v0 + v1) * T) / T ** 2
            c[3] = (-2.0 * (p1 - p0) + (v0 + v1) * T) / T ** 3
        else:
            c[1] = v0
            c[2] = 0.5 * a0
            c[3] = (20.0 * (p1 - p0) - (8.0 * v1 + 12.0 * v0) * T - (3.0 * a0 - a1) * T ** 2) / (2.0 * T ** 3)
            c[4] = (-30.0 * (p1 - p0) + (14.0 * v1 + 16.0 * v0) * T + (3.0 * a0 - 2.0 * a1) * T ** 2) / (2.0 * T ** 4)
            c[5] = (12.0 * (p1 - p0) - 6.0 * (v1 + v0) * T - (a0 - a1) * T ** 2) / (2.0 * T ** 5)
        return c

    def sample(self, t):
        """(position, velocity, acceleration) arrays at time t."""
        if not self.coefficients or t >= self.times[-1]:
            return self.positions[-1].copy(), np.zeros_like(self.positions[0]), np.zeros_like(self.positions[0])
        if t <= self.times[0]:
            return self.positions[0].copy(), self.velocities[0].copy(), self.accelerations[0].copy()
        if self._last is None or self._last[0] != t:
            i = int(np.searchsorted(self.times, t, side='right')) - 1
            powers = (t - self.times[i]) ** _POWERS
            self._last = (t, (powers.dot(self.coefficients[i]), powers[:5].dot(self.velocity_coefficients[i]),
                              powers[:4].dot(self.acceleration_coefficients[i])))
        position, velocity, acceleration = self._last[1]
        return position.copy(), velocity.copy(), acceleration.copy()


_POWERS = np.arange(6)


def stop_spline(start_time, position, velocity, duration):
    """The stop of a cancelled or preempted motion: to rest within `duration` s (stop_trajectory_duration).

    As the controller's hold: a quintic from the current state to
    position + velocity * duration / 2 with zero velocity.
    """
    position = np.asarray(position, dtype=float)
    velocity = np.asarray(velocity, dtype=float)
    if duration <= 0.0:
        return Spline([start_time], [position])
    end = position + velocity * duration / 2.0
    zeros = np.zeros_like(position)
    return Spline([start_time, start_time + duration], [position, end], [velocity, zeros], [zeros, zeros])


class Tolerances(object):
    """Per-joint tolerances (0: not checked), as joint_trajectory_controller keeps them."""

    def __init__(self, path_position, goal_position, goal_velocity, goal_time):
        self.path_position = np.array(path_position, dtype=float)
        self.path_velocity = np.zeros_like(self.path_position)
        self.goal_position = np.array(goal_position, dtype=float)
        self.goal_velocity = np.array(goal_velocity, dtype=float)
        self.goal_time = float(goal_time)

    @classmethod
    def from_constraints(cls, joints, constraints):
        """From a controller's `constraints` section of ur_robot_driver's <ur_type>_controllers.yaml."""
        constraints = constraints or {}
        per_joint = [constraints.get(name, {}) or {} for name in joints]
        stopped = float(constraints.get('stopped_velocity_tolerance', 0.01))
        return cls([float(j.get('trajectory', 0.0)) for j in per_joint],
                   [float(j.get('goal', 0.0)) for j in per_joint],
                   [stopped] * len(joints), float(constraints.get('goal_time', 0.0)))

    def for_goal(self, joints, path_tolerance, goal_tolerance, goal_time_tolerance):
        """A copy with a goal's JointTolerance lists (name, position, velocity) and goal time applied."""
        result = Tolerances(self.path_position, self.goal_position, self.goal_velocity, self.goal_time)
        result.path_velocity = self.path_velocity.copy()

        def apply(tolerances, position, velocity):
            for tolerance in tolerances:
                if tolerance.name not in joints:
                    continue
                j = joints.index(tolerance.name)
                for target, value in ((position, tolerance.position), (velocity, tolerance.velocity)):
                    if value > 0.0:
                        target[j] = value
                    elif value < 0.0:
                        target[j] = 0.0

        apply(path_tolerance, result.path_position, result.path_velocity)
        apply(goal_tolerance, result.goal_position, result.goal_velocity)
        if goal_time_tolerance > 0.0:
            result.goal_time = goal_time_tolerance
        return result

    @staticmethod
    def violated(error, tolerance):
        """Indices of joints whose |error| exceeds a checked (non-zero) tolerance."""
        return np.nonzero((tolerance > 0.0) & (np.abs(error) > tolerance))[0]
