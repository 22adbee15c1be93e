"""The arm's kinematics from the model in robot_description, without ROS.

Forward kinematics is kinematics.Model's chain product over the joints
between `base` and `tool0`, with the joint origins taken from the model once
(so the user's calibration, kinematics_config, is in them): the robot's own
`tool0_controller` is then the same frame as the model's `tool0`, as on a
calibrated robot. Inverse kinematics, for the Cartesian controllers and
movej to a pose, is damped least squares on that forward kinematics, from
the current joint positions (a Cartesian controller follows a path in small
steps, so it never needs a far jump); a target it cannot reach within the
tolerance is reported as such rather than approximated.

A planner going anywhere in the workspace needs every solution instead, which
a local search from one start does not find: nearest_inverse() takes the UR's
closed-form solutions (all eight branches) for the nominal geometry read from
the model's own joint origins, corrects them toward a calibrated model's (a
calibration moves the tool by millimetres to centimetres), finishes each with
the local search on the model, and returns the one nearest the start, in the
start's branch when that branch reaches.
"""

import itertools
import math

import numpy as np
from transforms3d.axangles import axangle2mat

from ur3_ft_gripper_description import kinematics

IDENTITY3 = np.eye(3)
# Joint positions whose kinematics are kept: a cycle's actual, target and commanded positions, and a spare.
CACHED_POSITIONS = 4


class ArmKinematics(object):
    def __init__(self, urdf_text, joints, base='base', tip='tool0'):
        # A control cycle asks for the same joint positions' kinematics many times (the tool pose, the
        # RTDE fields' speeds and elbow, force mode's Jacobian): each is computed once and kept
        # read-only; callers get copies.
        self._computed = {}
        model = kinematics.Model(urdf_text)
        root = model.root()
        if root is None or base not in model.links or tip not in model.links:
            raise ValueError('robot_description must be one tree holding %s and %s' % (base, tip))
        # ur_description's `base` hangs from base_link beside the arm, not above it.
        self.base_inverse = np.linalg.inv(model.chain_transform(model.chain(root, base)))
        self.chain = model.chain(root, tip)
        self.joints = list(joints)
        names = [joint.name for joint in self.chain]
        missing = [j for j in self.joints if j not in names]
        if missing:
            raise ValueError('robot_description has no joint(s) %s between %s and %s'
                             % (', '.join(missing), base, tip))
        self.index = [self.joints.index(j.name) if j.name in self.joints else None for j in self.chain]
        self.origins = [kinematics.pose_matrix(j.origin) for j in self.chain]
        self.axes = [np.asarray(j.axis or (1.0, 0.0, 0.0), dtype=float) for j in self.chain]
        self.lower = np.array([model.joints[j].limit.lower for j in self.joints], dtype=float)
        self.upper = np.array([model.joints[j].limit.upper for j in self.joints], dtype=float)
        self.velocity = np.array([model.joints[j].limit.velocity for j in self.joints], dtype=float)
        # The fixed joints before each moving one folded into one transform: the chain product then
        # takes one matrix product per moving joint.
        self.segments, fixed = [], self.base_inverse
        for joint, origin, axis, index in zip(self.chain, self.origins, self.axes, self.index):
            fixed = fixed.dot(origin)
            if index is not None:
                self.segments.append((fixed, joint, axis, index))
                fixed = np.eye(4)
        self.tail = fixed
        # forward() runs every control period: where every moving joint turns (a UR's do), their
        # rotations are made in one vectorised step by Rodrigues' formula, R = I + sin(q) K +
        # (1 - cos(q)) K^2 (K: the unit axis' cross-product matrix), each after its fixed transform.
        self.all_revolute = all(joint.type in ('revolute', 'continuous') for _, joint, _, _ in self.segments)
        self.segment_fixed = np.array([fixed for fixed, _, _, _ in self.segments])
        self.segment_joint = [index for _, _, _, index in self.segments]
        self.segment_axes = np.array([axis for _, _, axis, _ in self.segments])
        self.cross_matrices = np.array([kinematics.cross_matrix(axis) for axis in self.segment_axes])
        self.cross_squared = np.matmul(self.cross_matrices, self.cross_matrices)
        self.nominal = NominalUr.from_arm(self)

    def _links(self, positions):
        """Each moving joint's fixed transform times its rotation (all revolute), in chain order."""
        q = np.asarray(positions, dtype=float)[self.segment_joint][:, None, None]
        turns = IDENTITY3 + np.sin(q) * self.cross_matrices + (1.0 - np.cos(q)) * self.cross_squared
        links = self.segment_fixed.copy()
        links[:, :3, :3] = np.matmul(self.segment_fixed[:, :3, :3], turns)
        return links

    def forward(self, positions):
        """4x4 pose of the tip in the base for joint positions in `joints` order."""
        return self._chain(positions)[0].copy()

    def _chain(self, positions):
        """The tip's pose, and each actuated joint's axis and origin in the base (controller order), read-only."""
        key = np.asarray(positions, dtype=float).tobytes()
        computed = self._computed.get(key)
        if computed is None:
            computed = self._compute_chain(positions)
            for array in computed:
                array.setflags(write=False)
            if len(self._computed) >= CACHED_POSITIONS:
                del self._computed[next(iter(self._computed))]
            self._computed[key] = computed
        return computed

    def _compute_chain(self, positions):
        if self.all_revolute:
            # A joint turns about its own axis through its frame's origin: the frame after the turn
            # has the same axis and origin, so the running product of the links gives both.
            frames = [None] * len(self.segments)
            pose = np.eye(4)
            for i, link in enumerate(self._links(positions)):
                pose = frames[i] = pose.dot(link)
            frames = np.array(frames)
            axes, points = np.empty((len(self.joints), 3)), np.empty((len(self.joints), 3))
            axes[self.segment_joint] = np.einsum('nij,nj->ni', frames[:, :3, :3], self.segment_axes)
            points[self.segment_joint] = frames[:, :3, 3]
            return pose.dot(self.tail), axes, points
        t = np.eye(4)
        axes, points = np.empty((len(self.joints), 3)), np.empty((len(self.joints), 3))
        for fixed, joint, axis, index in self.segments:
            t = t.dot(fixed)
            axes[index] = t[:3, :3].dot(axis)
            points[index] = t[:3, 3].copy()
            t = t.dot(kinematics.motion_matrix(joint, positions[index]))
        return t.dot(self.tail), axes, points

    def joint_axes(self, positions):
        """(axes, origins): each actuated joint's axis and origin in the base, controller order."""
        return tuple(array.copy() for array in self._chain(positions)[1:])

    def jacobian(self, positions, tcp=None):
        """6xN geometric Jacobian of the tip in the base frame (revolute joints): linear, then angular.

        With `tcp` (4x4 in the tip's frame), of that point instead.
        """
        tip, axes, points = self._chain(positions)
        if tcp is not None:
            tip = tip.dot(tcp)
        axes = np.array(axes)
        return np.vstack([np.cross(axes, tip[:3, 3] - np.array(points)).T, axes.T])

    def inverse(self, target, seed, tolerance=1e-5, iterations=100, damping=1e-3):
        """Joint positions reaching the 4x4 `target` from `seed`, or None if not within tolerance."""
        q = np.array(seed, dtype=float)
        for _ in range(iterations):
            error = pose_error(target, self.forward(q))
            if np.linalg.norm(error) < tolerance:
                return q
            jac = self.jacobian(q)
            step = jac.T.dot(np.linalg.solve(jac.dot(jac.T) + damping ** 2 * np.eye(6), error))
            q = np.clip(q + step, self.lower, self.upper)
        return q if np.linalg.norm(pose_error(target, self.forward(q))) < tolerance else None

    def nearest_inverse(self, target, seed, tolerance=1e-8):
        """Joint positions within the limits reaching the 4x4 `target`, or None if it is out of reach: of
        the solutions, the one nearest `seed` in the seed's branch (shoulder, wrist, elbow) if that branch
        reaches, else the nearest of all. Each joint goes the short way round from the seed."""
        seed = np.asarray(seed, dtype=float)
        # Last, the local search from the seed alone, for a chain not shaped like a UR's.
        for start in itertools.chain(self.branch_starts(target, seed), [seed]):
            start = self.nearest_equivalent(start, seed)
            joints = None if start is None else self.inverse(target, start, tolerance=tolerance)
            joints = None if joints is None else self.nearest_equivalent(joints, seed)
            if joints is not None:
                return joints
        return None

    def branch_starts(self, target, seed):
        """Starts of the local search (`joints` order) for `target`, one per branch the nominal arm
        reaches: the seed's branch first, then the nearest first."""
        nominal = self.nominal
        if nominal is None:
            return
        own_branch = nominal.branch_of(seed[nominal.order])
        wrist_3 = seed[nominal.order[5]]
        # The seed's branch alone first: it is the answer wherever it reaches, the others are not needed.
        for branch, q, excess in nominal.solutions(target, wrist_3, own_branch):
            start = self.corrected_start(target, branch, q, excess)
            if start is not None:
                yield start
        others = [(float(np.linalg.norm(wrapped(self.from_nominal(q) - seed))), branch, q, excess)
                  for branch, q, excess in nominal.solutions(target, wrist_3) if branch != own_branch]
        for _, branch, q, excess in sorted(others, key=lambda other: other[0]):
            start = self.corrected_start(target, branch, q, excess)
            if start is not None:
                yield start

    def corrected_start(self, target, branch, q, excess):
        """The nominal arm's solution `q` of `branch` for `target` (DH order), corrected toward the model's
        where the model is calibrated, in `joints` order; None if the branch does not reach."""
        nominal = self.nominal
        for _ in range(0 if nominal.exact else NOMINAL_CORRECTIONS):
            # Near these joints the model differs from the nominal arm by about the same transform: the
            # nominal arm's solution for the target moved by it is closer to the model's.
            corrected = target.dot(rigid_inverse(self.forward(self.from_nominal(q)))).dot(nominal.forward(q))
            solved = nominal.solutions(corrected, q[5], branch)
            if not solved:
                break  # the wrist centre on shoulder_pan's axis: the local search takes it from here
            _, q, excess = solved[0]
        return self.from_nominal(q) if excess <= NOMINAL_REACH_SLACK else None

    def from_nominal(self, q):
        """Joint positions in `joints` order from the nominal arm's (DH order)."""
        positions = np.empty(len(self.joints))
        positions[self.nominal.order] = q
        return positions

    def nearest_equivalent(self, positions, seed):
        """`positions` with each joint turned by whole turns to lie nearest `seed` within the limits, or
        None if a joint has no turn within its limits."""
        turn = 2.0 * math.pi
        lower, upper = self.lower - LIMIT_SLACK, self.upper + LIMIT_SLACK
        q = np.asarray(positions, dtype=float)
        q = q + turn * np.round((np.asarray(seed, dtype=float) - q) / turn)
        q = np.where(q > upper, q - turn, q)
        q = np.where(q < lower, q + turn, q)
        return np.clip(q, self.lower, self.upper) if np.all((q >= lower) & (q <= upper)) else None


# A solution this far (rad) beyond a joint limit is on it: one found at 0 is at a limit of 2 pi too.
LIMIT_SLACK = 1e-9
# The nominal arm only seeds the search on the model: a branch is tried if it misses the pose by this
# much (in the arccosines' arguments), as a calibrated arm may still reach it.
NOMINAL_REACH_SLACK = 0.01
# Corrections of the nominal solution toward a calibrated model's, before the local search finishes.
NOMINAL_CORRECTIONS = 3


class NominalUr(object):
    """The UR's closed-form inverse kinematics, all eight branches (K. P. Hawkins, "Analytic Inverse
    Kinematics for the Universal Robots UR-5/UR-10 Arms", 2013), for the Denavit-Hartenberg parameters
    of ur_description's joint origins: there, base_link_inertia is DH frame 0 and each link's frame is
    the DH frame of its joint, so d1, a2, a3, d4, d5, d6 are origin coordinates. A calibration moves
    the origins off that form: `exact` says whether the model is the nominal arm."""

    ALPHA = (math.pi / 2.0, 0.0, 0.0, math.pi / 2.0, -math.pi / 2.0, 0.0)

    def __init__(self, d1, a2, a3, d4, d5, d6, base, tip, order):
        self.d = (d1, 0.0, 0.0, d4, d5, d6)
        self.a = (0.0, a2, a3, 0.0, 0.0, 0.0)
        self.base, self.tip = base, tip  # arm's base -> DH frame 0, DH frame 6 -> arm's tip
        self.base_inverse, self.tip_inverse = rigid_inverse(base), rigid_inverse(tip)
        self.order = order  # the arm's joint index of each DH joint
        self.exact = False

    @classmethod
    def from_arm(cls, arm):
        """The nominal arm of an ArmKinematics, or None if its chain is not shaped like a UR's."""
        actuated = [joint for joint in arm.chain if joint.name in arm.joints]
        if len(actuated) != 6 or any(joint.origin is None or list(joint.axis or ()) != [0.0, 0.0, 1.0]
                                     for joint in actuated):
            return None
        xyz = [list(joint.origin.xyz or (0.0, 0.0, 0.0)) for joint in actuated]
        d1, a2, a3, d4, d5, d6 = xyz[0][2], xyz[2][0], xyz[3][0], xyz[3][2], -xyz[4][1], xyz[5][1]
        first, last = arm.chain.index(actuated[0]), arm.chain.index(actuated[-1])
        base = arm.base_inverse
        for origin in arm.origins[:first + 1]:
            base = base.dot(origin)
        base = base.dot(translation(0.0, 0.0, -d1))
        tip = np.eye(4)
        for origin in arm.origins[last + 1:]:
            tip = tip.dot(origin)
        nominal = cls(d1, a2, a3, d4, d5, d6, base, tip, [arm.joints.index(joint.name) for joint in actuated])
        nominal.exact = True
        for q in (np.zeros(6), np.array([0.5, -1.0, 1.2, -1.5, -1.2, 0.7])):
            positions = np.empty(6)
            positions[nominal.order] = q
            # The model's rounding of pi/2 in its origins moves the tool by less than a micrometre.
            nominal.exact = nominal.exact and np.abs(nominal.forward(q) - arm.forward(positions)).max() < 1e-6
        return nominal

    def link(self, i, theta):
        """DH transform of joint i (0-based) at angle theta."""
        ct, st = math.cos(theta), math.sin(theta)
        ca, sa = math.cos(self.ALPHA[i]), math.sin(self.ALPHA[i])
        return np.array([[ct, -st * ca, st * sa, self.a[i] * ct],
                         [st, ct * ca, -ct * sa, self.a[i] * st],
                         [0.0, sa, ca, self.d[i]],
                         [0.0, 0.0, 0.0, 1.0]])

    def flange(self, q):
        """DH frame 6 in DH frame 0 for joints q (DH order)."""
        t = np.eye(4)
        for i in range(6):
            t = t.dot(self.link(i, q[i]))
        return t

    def forward(self, q):
        """The nominal arm's tip in the arm's base, joints q in DH order."""
        return self.base.dot(self.flange(q)).dot(self.tip)

    def solutions(self, target, wrist_3=0.0, branch=None):
        """(branch, joints in DH order, excess) for each branch (or only `branch`) of the 4x4 `target`
        (the tip in the arm's base). Where the nominal arm cannot reach, its joints come as near as
        they go and `excess` says by how much the arm falls short (0 where it reaches); `wrist_3` is
        taken where the wrist is straight and any wrist_3 angle would do."""
        return self._solve(self.base_inverse.dot(target).dot(self.tip_inverse), wrist_3, branch)

    def branch_of(self, q):
        """The branch of joints q (DH order) as solutions() names it: (shoulder, wrist, elbow), each +1 or
        -1, or 0 where two branches meet."""
        a2, a3, d5 = self.a[1], self.a[2], self.d[4]
        # The wrist centre (DH frame 5's origin) along DH frame 1's x axis: the shoulder's two solutions
        # put it ahead and behind.
        ahead = a2 * math.cos(q[1]) + a3 * math.cos(q[1] + q[2]) + d5 * math.sin(q[1] + q[2] + q[3])
        return int(-np.sign(ahead)), int(np.sign(math.sin(q[4]))), int(np.sign(math.sin(q[2])))

    def _solve(self, flange, wrist_3, wanted=None):
        d4, d6 = self.d[3], self.d[5]
        a2, a3 = self.a[1], self.a[2]
        rotation = flange[:3, :3]
        wrist = flange[:3, 3] - d6 * rotation[:, 2]  # DH frame 5's origin
        radius = math.hypot(wrist[0], wrist[1])
        if radius == 0.0:
            return []
        found = []
        shoulder, shoulder_excess = clipped_arccos(d4 / radius)
        for shoulder_sign in (1, -1):
            q1 = math.atan2(wrist[1], wrist[0]) + shoulder_sign * shoulder + math.pi / 2.0
            s1, c1 = math.sin(q1), math.cos(q1)
            tilt, tilt_excess = clipped_arccos((flange[0, 3] * s1 - flange[1, 3] * c1 - d4) / d6)
            for wrist_sign in (1, -1):
                if wanted is not None and wanted[:2] != (shoulder_sign, wrist_sign):
                    continue
                q5 = wrist_sign * tilt
                s5 = math.sin(q5)
                if abs(s5) < 1e-9:
                    q6 = wrist_3  # wrist_1 and wrist_3 in line: the elbow chain takes up the difference
                else:
                    q6 = math.atan2((-rotation[0, 1] * s1 + rotation[1, 1] * c1) / s5,
                                    (rotation[0, 0] * s1 - rotation[1, 0] * c1) / s5)
                to_wrist_1 = rigid_inverse(self.link(0, q1)).dot(flange).dot(
                    rigid_inverse(self.link(4, q5).dot(self.link(5, q6))))
                reach = to_wrist_1.dot([0.0, -d4, 0.0, 1.0])[:3]  # wrist_1's joint in DH frame 1
                length = float(np.linalg.norm(reach))
                if length == 0.0:
                    continue
                bend, bend_excess = clipped_arccos((length ** 2 - a2 ** 2 - a3 ** 2) / (2.0 * a2 * a3))
                for elbow_sign in (1, -1):
                    if wanted is not None and wanted[2] != elbow_sign:
                        continue
                    q3 = elbow_sign * bend
                    q2 = -math.atan2(reach[1], -reach[0]) + math.asin(
                        max(-1.0, min(1.0, a3 * math.sin(q3) / length)))
                    wrist_1 = rigid_inverse(self.link(1, q2).dot(self.link(2, q3))).dot(to_wrist_1)
                    q4 = math.atan2(wrist_1[1, 0], wrist_1[0, 0])
                    found.append(((shoulder_sign, wrist_sign, elbow_sign), np.array([q1, q2, q3, q4, q5, q6]),
                                  max(shoulder_excess, tilt_excess, bend_excess)))
        return found


def clipped_arccos(value):
    """(arccos of `value` clipped to [-1, 1], how far `value` lies beyond)."""
    return math.acos(max(-1.0, min(1.0, value))), max(0.0, abs(value) - 1.0)


def wrapped(angles):
    """Angles (rad) brought into [-pi, pi)."""
    return (np.asarray(angles) + math.pi) % (2.0 * math.pi) - math.pi


def rigid_inverse(transform):
    """Inverse of a 4x4 rotation and translation."""
    inverse = np.eye(4)
    inverse[:3, :3] = transform[:3, :3].T
    inverse[:3, 3] = -transform[:3, :3].T.dot(transform[:3, 3])
    return inverse


def translation(x, y, z):
    t = np.eye(4)
    t[:3, 3] = (x, y, z)
    return t


def rotation_matrix(vector):
    """Rotation matrix of a rotation vector (the exp map; URScript's rx, ry, rz)."""
    vector = np.asarray(vector, dtype=float)
    angle = float(np.linalg.norm(vector))
    return axangle2mat(vector / angle, angle) if angle > 0.0 else np.eye(3)


def rotation_vector(rotation):
    """Rotation vector of a rotation matrix (the log map), exact for small angles too."""
    v = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0], rotation[1, 0] - rotation[0, 1]])
    sine = np.linalg.norm(v) / 2.0
    angle = np.arctan2(sine, (np.trace(rotation) - 1.0) / 2.0)
    if sine < 1e-9:
        if angle < 1.0:
            return v / 2.0
        # Half a turn: R = 2 a a^T - I, so a a^T = (R + I) / 2; its largest diagonal term's column is
        # the axis, scaled (a closed form of mat2axangle's eigenvector, without an eigensolver).
        outer = (rotation + rotation.T + 2.0 * np.eye(3)) / 4.0
        k = int(np.argmax(np.diag(outer)))
        axis = outer[:, k] / np.sqrt(outer[k, k])
        return (-axis if axis.dot(v) < 0.0 else axis) * angle
    return v * angle / (2.0 * sine)


def pose_error(target, current):
    """6-vector from `current` to `target`: translation, then rotation vector (base frame)."""
    return np.concatenate([target[:3, 3] - current[:3, 3], rotation_vector(target[:3, :3].dot(current[:3, :3].T))])
