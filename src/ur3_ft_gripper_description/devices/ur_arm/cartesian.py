"""The arm's Cartesian motions, without ROS.

- A Cartesian trajectory (the Cartesian controllers' goals) becomes
  joint-space points: the tool's path is interpolated between the waypoints
  (straight line, slerp) in short steps, and each step is solved by inverse
  kinematics from the previous one, so the joints follow that path and not
  just its corners. A path that leaves the arm's reach, or that a branch
  change or singularity would make the joints jump along, is refused, as the
  driver refuses a goal it cannot run.
- A twist (twist_controller, the robot's speedl) moves a commanded tool pose
  exactly by the twist; the joints are steered to that pose, so the error of
  the linearisation does not pile up as drift.
"""

import collections
import math

import numpy as np
from transforms3d.quaternions import quat2mat

from .arm_kinematics import pose_error, rotation_matrix, rotation_vector
from .trajectory import GoalError, Point

# Time between two solved poses of a Cartesian path, s.
PATH_STEP = 0.02
# The largest joint motion (rad) between two solved poses that is still the same branch of the path.
BRANCH_JUMP = 0.5
# How far (m, rad) the commanded pose may run ahead of the tool before it is dropped.
TWIST_CATCH_UP = 0.01
# Newton steps a cycle: a long cycle (a loaded machine) must not leave a second-order error.
TWIST_NEWTON_STEPS = 4

# One point of a Cartesian trajectory: time from start (s), position (m), orientation quaternion (w, x, y, z).
Waypoint = collections.namedtuple('Waypoint', 'time position orientation')


def interpolate_pose(start, end, fraction):
    """Straight line and slerp between two 4x4 poses."""
    pose = np.eye(4)
    pose[:3, 3] = start[:3, 3] + fraction * (end[:3, 3] - start[:3, 3])
    turn = rotation_vector(end[:3, :3].dot(start[:3, :3].T))
    pose[:3, :3] = rotation_matrix(fraction * turn).dot(start[:3, :3])
    return pose


def pose_from_ur_pose(ur_pose):
    """4x4 pose of a URScript pose p[x, y, z, rx, ry, rz] (a position and a rotation vector)."""
    pose = np.eye(4)
    pose[:3, :3] = rotation_matrix(ur_pose[3:])
    pose[:3, 3] = ur_pose[:3]
    return pose


def _waypoint_pose(index, waypoint, previous_time):
    """The 4x4 pose of a checked waypoint; GoalError (INVALID_GOAL) for what the driver refuses."""
    w, x, y, z = waypoint.orientation
    if not all(math.isfinite(v) for v in (w, x, y, z, waypoint.time) + tuple(waypoint.position)):
        raise GoalError('INVALID_GOAL', 'Point %d holds a NaN or infinite value' % index)
    norm = math.sqrt(w ** 2 + x ** 2 + y ** 2 + z ** 2)
    if abs(norm - 1.0) > 1e-3:
        raise GoalError('INVALID_GOAL', 'Point %d has an illegal quaternion (norm %.4f, not 1)' % (index, norm))
    if waypoint.time <= previous_time:
        raise GoalError('INVALID_GOAL', 'Point %d: times must be strictly increasing (and above 0)' % index)
    pose = np.eye(4)
    pose[:3, :3] = quat2mat((w / norm, x / norm, y / norm, z / norm))
    pose[:3, 3] = waypoint.position
    return pose


def joint_path(arm, waypoints, start):
    """Joint-space Points following the tool's path through `waypoints` (in the base frame) from joints `start`.

    `arm` is an ArmKinematics. Raises GoalError (INVALID_GOAL) for an empty or
    malformed trajectory and for a path the arm cannot follow.
    """
    if not waypoints:
        raise GoalError('INVALID_GOAL', 'The Cartesian trajectory has no points')
    poses, times = [arm.forward(start)], [0.0]
    for index, waypoint in enumerate(waypoints):
        poses.append(_waypoint_pose(index, waypoint, times[-1]))
        times.append(waypoint.time)
    result, seed = [], np.asarray(start, dtype=float)
    for i in range(1, len(poses)):
        steps = max(1, int(math.ceil((times[i] - times[i - 1]) / PATH_STEP)))
        for k in range(1, steps + 1):
            fraction = float(k) / steps
            joints = arm.inverse(interpolate_pose(poses[i - 1], poses[i], fraction), seed)
            if joints is None:
                raise GoalError('INVALID_GOAL', 'Point %d (%.3f, %.3f, %.3f) is out of reach of the arm '
                                '(no inverse kinematics solution near the path)' % (
                                    i - 1, poses[i][0, 3], poses[i][1, 3], poses[i][2, 3]))
            if np.max(np.abs(joints - seed)) > BRANCH_JUMP:
                raise GoalError('INVALID_GOAL', 'Point %d: the path passes a singularity or changes the '
                                'arm configuration' % (i - 1))
            result.append(Point(times[i - 1] + fraction * (times[i] - times[i - 1]), joints))
            seed = joints
    return result


class TwistFollower(object):
    """speedl: the commanded tool pose moves by the twist exactly; what is not commanded stays put."""

    def __init__(self, arm):
        self.arm = arm
        self.pose = None  # the commanded tool pose (4x4) while a twist is followed

    def reset(self):
        """The next step starts from where the tool is."""
        self.pose = None

    def step(self, q, twist, dt):
        """Joint positions after `dt` s of the 6-vector `twist` (base frame: linear, then angular) from `q`."""
        actual = self.arm.forward(q)
        if self.pose is None:
            self.pose = actual
        pose = self.pose.copy()
        pose[:3, 3] += twist[:3] * dt
        pose[:3, :3] = rotation_matrix(np.asarray(twist[3:], dtype=float) * dt).dot(pose[:3, :3])
        # A pose the joints cannot follow (limits, singularity) is not chased later: start from where they are.
        if np.linalg.norm(pose_error(pose, actual)) > TWIST_CATCH_UP:
            self.pose = actual
            return np.array(q, dtype=float)
        self.pose = pose
        solution = np.array(q, dtype=float)
        for _ in range(TWIST_NEWTON_STEPS):
            error = pose_error(pose, self.arm.forward(solution))
            if np.linalg.norm(error) < 1e-10:
                break
            solution = solution + np.linalg.lstsq(self.arm.jacobian(solution), error, rcond=None)[0]
        return solution
