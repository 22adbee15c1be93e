"""Forward kinematics straight from URDF text (numpy only, no ROS master).

Used where the package must compute from the model itself rather than from
typed-in numbers: expected transforms in tests, the gripper opening <-> finger
angle mapping, the TCP location.
"""

import xml.dom.minidom

import numpy as np


def rpy_matrix(roll, pitch, yaw):
    """Rotation matrix of URDF fixed-axis roll, pitch, yaw (Rz(yaw) Ry(pitch) Rx(roll))."""
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr]])


def transform(xyz=(0, 0, 0), rpy=(0, 0, 0)):
    t = np.eye(4)
    t[:3, :3] = rpy_matrix(*rpy)
    t[:3, 3] = xyz
    return t


def quaternion_matrix(x, y, z, w):
    """Rotation matrix of a unit quaternion (as in geometry_msgs/Quaternion)."""
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def transform_msg_matrix(msg):
    """4x4 matrix of a geometry_msgs/Transform."""
    t = np.eye(4)
    q = msg.rotation
    t[:3, :3] = quaternion_matrix(q.x, q.y, q.z, q.w)
    t[:3, 3] = [msg.translation.x, msg.translation.y, msg.translation.z]
    return t


def axis_angle_matrix(axis, angle):
    """Rotation about a unit axis (Rodrigues)."""
    x, y, z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k.dot(k)


def _floats(text, default):
    return [float(v) for v in text.split()] if text else list(default)


class Joint(object):
    def __init__(self, element):
        self.name = element.getAttribute('name')
        self.type = element.getAttribute('type')
        self.parent = element.getElementsByTagName('parent')[0].getAttribute('link')
        self.child = element.getElementsByTagName('child')[0].getAttribute('link')
        origin = element.getElementsByTagName('origin')
        xyz = _floats(origin[0].getAttribute('xyz'), (0, 0, 0)) if origin else [0, 0, 0]
        rpy = _floats(origin[0].getAttribute('rpy'), (0, 0, 0)) if origin else [0, 0, 0]
        self.origin = transform(xyz, rpy)
        axis = element.getElementsByTagName('axis')
        self.axis = _floats(axis[0].getAttribute('xyz'), (1, 0, 0)) if axis else [1.0, 0.0, 0.0]
        limit = element.getElementsByTagName('limit')
        self.lower = float(limit[0].getAttribute('lower') or 0) if limit else None
        self.upper = float(limit[0].getAttribute('upper') or 0) if limit else None
        mimic = element.getElementsByTagName('mimic')
        self.mimic = None
        if mimic:
            m = mimic[0]
            self.mimic = (m.getAttribute('joint'),
                          float(m.getAttribute('multiplier') or 1.0),
                          float(m.getAttribute('offset') or 0.0))

    def motion(self, position):
        """Transform that the joint's own motion adds after its origin."""
        t = np.eye(4)
        if self.type in ('revolute', 'continuous'):
            t[:3, :3] = axis_angle_matrix(self.axis, position)
        elif self.type == 'prismatic':
            t[:3, 3] = np.asarray(self.axis, dtype=float) * position
        return t


class Model(object):
    """Links and joints of a URDF, with forward kinematics between any two links."""

    def __init__(self, urdf_text):
        robot = xml.dom.minidom.parseString(urdf_text).documentElement
        self.links = [e.getAttribute('name') for e in robot.childNodes
                      if e.nodeType == e.ELEMENT_NODE and e.tagName == 'link']
        self.joints = {}
        for e in robot.childNodes:
            if e.nodeType == e.ELEMENT_NODE and e.tagName == 'joint':
                joint = Joint(e)
                self.joints[joint.name] = joint
        self.parent_joint = {j.child: j for j in self.joints.values()}
        self.link_elements = {e.getAttribute('name'): e for e in robot.childNodes
                              if e.nodeType == e.ELEMENT_NODE and e.tagName == 'link'}

    def root(self):
        roots = [lk for lk in self.links if lk not in self.parent_joint]
        return roots[0] if len(roots) == 1 else None

    def path_to_root(self, link):
        path = [link]
        while path[-1] in self.parent_joint:
            path.append(self.parent_joint[path[-1]].parent)
        return path

    def chain(self, from_link, to_link):
        """Joints from `from_link` down to `to_link` (which must be its descendant)."""
        up = self.path_to_root(to_link)
        if from_link not in up:
            raise ValueError('%s is not above %s' % (from_link, to_link))
        links = list(reversed(up[:up.index(from_link)]))
        return [self.parent_joint[lk] for lk in links]

    def position(self, joint, positions):
        if joint.mimic:
            source, multiplier, offset = joint.mimic
            return positions.get(source, 0.0) * multiplier + offset
        return positions.get(joint.name, 0.0)

    def chain_transform(self, joints, positions=None):
        """Product of the joints' origins and motions, e.g. of a list from chain()."""
        positions = positions or {}
        t = np.eye(4)
        for joint in joints:
            t = t.dot(joint.origin).dot(joint.motion(self.position(joint, positions)))
        return t

    def to_root(self, link, positions=None):
        """Pose of `link` in the root frame."""
        root = self.root()
        return self.chain_transform(self.chain(root, link) if link != root else [], positions)

    def transform(self, from_link, to_link, positions=None):
        """Pose of `to_link` in `from_link` (what tf2 lookup_transform(from, to) returns)."""
        return np.linalg.inv(self.to_root(from_link, positions)).dot(self.to_root(to_link, positions))


def matrix_rpy(rotation):
    """URDF roll, pitch, yaw of a rotation matrix (inverse of rpy_matrix, pitch in [-pi/2, pi/2])."""
    r = np.asarray(rotation, dtype=float)
    pitch = np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0]))
    if np.hypot(r[0, 0], r[1, 0]) < 1e-12:  # gimbal lock: put it all in roll
        return float(np.arctan2(-r[1, 2], r[1, 1])), float(pitch), 0.0
    return (float(np.arctan2(r[2, 1], r[2, 2])), float(pitch), float(np.arctan2(r[1, 0], r[0, 0])))
