"""Forward kinematics of a URDF, without a ROS master.

urdf_parser_py reads the model and transforms3d does the rotations. The
product along a chain stays here, a few lines: no Python library that is
both a Noetic rosdep key and a Debian 12 package computes URDF forward
kinematics with mimic joints (kdl_parser_py is not in Debian 12).

Used where the package must compute from the model itself rather than from
typed-in numbers: the pad gap <-> finger_joint mapping, the TCP pose, and the
expected transforms in tests.
"""

import numpy as np
from transforms3d.axangles import axangle2mat
from transforms3d.euler import euler2mat, mat2euler
from urdf_parser_py import xml_reflection
from urdf_parser_py.urdf import URDF

# urdf_parser_py reports every attribute it does not know (upstream meshes'
# inertials carry some) on stderr; the model is read all the same.
xml_reflection.core.on_error = lambda message: None


def rpy_matrix(roll, pitch, yaw):
    """Rotation matrix of URDF's fixed-axis roll, pitch, yaw."""
    return euler2mat(roll, pitch, yaw, 'sxyz')


def matrix_rpy(rotation):
    """URDF roll, pitch, yaw of a rotation matrix (inverse of rpy_matrix)."""
    return tuple(float(angle) for angle in mat2euler(rotation, 'sxyz'))


def pose_matrix(pose):
    """4x4 matrix of a urdf_parser_py Pose (None: identity)."""
    t = np.eye(4)
    if pose is not None:
        t[:3, :3] = rpy_matrix(*(pose.rpy or (0.0, 0.0, 0.0)))
        t[:3, 3] = pose.xyz or (0.0, 0.0, 0.0)
    return t


def motion_matrix(joint, position):
    """Transform that a joint's own motion adds after its origin."""
    t = np.eye(4)
    axis = joint.axis or (1.0, 0.0, 0.0)  # URDF's default axis
    if joint.type in ('revolute', 'continuous'):
        t[:3, :3] = axangle2mat(axis, position)
    elif joint.type == 'prismatic':
        t[:3, 3] = np.asarray(axis, dtype=float) * position
    return t


def cross_matrix(axis):
    """K with K v = unit(axis) x v: Rodrigues' formula turns by q as I + sin(q) K + (1 - cos(q)) K^2."""
    x, y, z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def motion_matrices(joint, positions):
    """motion_matrix for each of an array of `positions`: an (n, 4, 4) stack (Rodrigues' formula)."""
    positions = np.asarray(positions, dtype=float)
    t = np.broadcast_to(np.eye(4), positions.shape + (4, 4)).copy()
    axis = np.asarray(joint.axis or (1.0, 0.0, 0.0), dtype=float)
    if joint.type in ('revolute', 'continuous'):
        cross = cross_matrix(axis)
        turns = positions[..., None, None]
        t[..., :3, :3] += np.sin(turns) * cross + (1.0 - np.cos(turns)) * cross.dot(cross)
    elif joint.type == 'prismatic':
        t[..., :3, 3] = positions[..., None] * axis
    return t


class Model(object):
    """A URDF (urdf_parser_py's `robot`) with forward kinematics between any two links."""

    def __init__(self, urdf_text):
        self.robot = URDF.from_xml_string(urdf_text)
        self.links = [link.name for link in self.robot.links]
        self.joints = self.robot.joint_map
        self.parent_joint = {joint.child: joint for joint in self.robot.joints}
        # Each joint's origin as a matrix, made once: tests and exports ask for chains thousands of times.
        self.origin_matrix = {joint.name: pose_matrix(joint.origin) for joint in self.robot.joints}

    def root(self):
        roots = [link for link in self.links if link not in self.parent_joint]
        return roots[0] if len(roots) == 1 else None

    def chain(self, from_link, to_link):
        """Joints from `from_link` down to `to_link` (which must be its descendant)."""
        joints = []
        link = to_link
        while link != from_link:
            if link not in self.parent_joint:
                raise ValueError('%s is not above %s' % (from_link, to_link))
            joints.append(self.parent_joint[link])
            link = joints[-1].parent
        return joints[::-1]

    def position(self, joint, positions):
        if joint.mimic is not None:
            mimic = joint.mimic
            return (positions.get(mimic.joint, 0.0) * (1.0 if mimic.multiplier is None else mimic.multiplier)
                    + (mimic.offset or 0.0))
        return positions.get(joint.name, 0.0)

    def origin(self, joint):
        """The 4x4 origin of `joint`: kept for the model's own joints, converted for any other."""
        return self.origin_matrix[joint.name] if self.joints.get(joint.name) is joint else pose_matrix(joint.origin)

    def chain_transform(self, joints, positions=None):
        """Product of the joints' origins and motions, e.g. of a list from chain()."""
        positions = positions or {}
        t = np.eye(4)
        for joint in joints:
            t = t.dot(self.origin(joint)).dot(motion_matrix(joint, self.position(joint, positions)))
        return t

    def chain_transforms(self, joints, positions):
        """chain_transform for many joint states at once: `positions` maps joint names to arrays of one
        length n (a joint it leaves out stands at 0); an (n, 4, 4) stack."""
        count = len(next(iter(positions.values())))
        zeros = np.zeros(count)
        t = np.broadcast_to(np.eye(4), (count, 4, 4))
        for joint in joints:
            moved = np.broadcast_to(self.position(joint, positions), (count,)) if joint.type != 'fixed' else zeros
            t = np.matmul(np.matmul(t, self.origin(joint)), motion_matrices(joint, moved))
        return t

    def transform(self, from_link, to_link, positions=None):
        """Pose of `to_link` in `from_link` (what tf2 lookup_transform(from, to) returns)."""
        root = self.root()
        to_root = [self.chain_transform(self.chain(root, link), positions) for link in (from_link, to_link)]
        return np.linalg.inv(to_root[0]).dot(to_root[1])
