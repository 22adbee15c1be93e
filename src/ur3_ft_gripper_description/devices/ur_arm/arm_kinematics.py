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
"""

import numpy as np
from transforms3d.axangles import axangle2mat, mat2axangle

from ur3_ft_gripper_description import kinematics


class ArmKinematics(object):
    def __init__(self, urdf_text, joints, base='base', tip='tool0'):
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

    def forward(self, positions):
        """4x4 pose of the tip in the base for joint positions in `joints` order."""
        return self._chain(positions)[0]

    def _chain(self, positions):
        """The tip's pose, and each actuated joint's axis and origin in the base (controller order)."""
        t = self.base_inverse
        axes, points = [None] * len(self.joints), [None] * len(self.joints)
        for joint, origin, axis, index in zip(self.chain, self.origins, self.axes, self.index):
            t = t.dot(origin)
            if index is not None:
                axes[index] = t[:3, :3].dot(axis)
                points[index] = t[:3, 3].copy()
                t = t.dot(kinematics.motion_matrix(joint, positions[index]))
        return t, axes, points

    def jacobian(self, positions):
        """6xN geometric Jacobian of the tip in the base frame (revolute joints): linear, then angular."""
        tip, axes, points = self._chain(positions)
        linear = [np.cross(axis, tip[:3, 3] - point) for axis, point in zip(axes, points)]
        return np.vstack([np.array(linear).T, np.array(axes).T])

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
        axis, angle = mat2axangle(rotation)  # half a turn: the axis from the matrix itself
        return np.asarray(axis) * angle
    return v * angle / (2.0 * sine)


def pose_error(target, current):
    """6-vector from `current` to `target`: translation, then rotation vector (base frame)."""
    return np.concatenate([target[:3, 3] - current[:3, 3], rotation_vector(target[:3, :3].dot(current[:3, :3].T))])
