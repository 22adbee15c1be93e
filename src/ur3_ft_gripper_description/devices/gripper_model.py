"""2F-140 opening <-> finger_joint angle, derived from the model's own finger kinematics.

Pure numpy (no ROS imports). The mapping is not typed in: it is computed by
forward kinematics of the expanded URDF (mimic joints included), as the gap
between the inner faces of ``left_inner_finger_pad`` and
``right_inner_finger_pad``, so it follows whatever robotiq variant is on the
ROS_PACKAGE_PATH.
"""

import numpy as np

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.model.names import FINGER_JOINT, PADS
from ur3_ft_gripper_description import yaml_data



def load_gripper_spec(path, keys=('stroke',)):
    """The `gripper` section of a YAML file like config/sim_devices.yaml; ValueError if a key is missing."""
    with open(path) as f:
        data = yaml_data.load(f) or {}
    spec = data.get('gripper') if isinstance(data, dict) else None
    if not isinstance(spec, dict):
        raise ValueError("%s: no 'gripper' section" % path)
    missing = [k for k in keys if k not in spec]
    if missing:
        raise ValueError("%s: the 'gripper' section has no %s" % (path, ', '.join(missing)))
    return spec


class RegisterScale(object):
    """The 2F-140's position register (gPO, rPR) <-> the opening between its pads, in m.

    2F-85 & 2F-140 Instruction Manual, section 4: the register is a position
    scale, 0x00 full opening .. 0xFF full closing. A unit reports `gpo_open`
    fully open and `gpo_closed` fully closed (config/sim_devices.yaml has the
    defaults and their sources), and the opening is linear in between:
    ``stroke * (gpo_closed - gPO) / (gpo_closed - gpo_open)``, clamped to 0..stroke.
    """

    def __init__(self, stroke, gpo_open, gpo_closed):
        if not (stroke > 0 and 0 <= gpo_open < gpo_closed <= 255):
            raise ValueError('need stroke > 0 and 0 <= gpo_open < gpo_closed <= 255, got %r, %r, %r'
                             % (stroke, gpo_open, gpo_closed))
        self.stroke, self.gpo_open, self.gpo_closed = float(stroke), float(gpo_open), float(gpo_closed)

    @property
    def counts_per_metre(self):
        return (self.gpo_closed - self.gpo_open) / self.stroke

    def opening(self, gpo):
        """Pad opening (m) for position register value `gpo`."""
        width = (self.gpo_closed - float(gpo)) / self.counts_per_metre
        return min(max(width, 0.0), self.stroke)

    def position(self, opening):
        """Position register value (float) for a pad opening of `opening` m."""
        return self.gpo_closed - float(opening) * self.counts_per_metre


def step_toward(current, target, speed, dt):
    """Where a point at `current` moving at most `speed` for `dt` towards `target` ends up."""
    if speed < 0 or dt < 0:
        raise ValueError('speed and dt must be >= 0, got %r and %r' % (speed, dt))
    reach = speed * dt
    delta = target - current
    if abs(delta) <= reach:
        return target
    return current + np.copysign(reach, delta)


def _pad_box(link):
    """Box size of a pad link (urdf_parser_py; collision first, else visual), or None if it is no box."""
    for part in list(link.collisions) + list(link.visuals):
        size = getattr(part.geometry, 'size', None)
        if size is not None:
            return [float(v) for v in size]
    return None


def pad_gap(left, right, box):
    """Gap between the inner faces of two pads with poses `left`, `right` (4x4) and box size `box`.

    The pad normal is the pad axis best aligned with the line between the
    pads' centres; the gap is the centres' distance along it, less one pad
    thickness (half of each pad's box along that axis).
    """
    return float(pad_gaps(left[None], right[None], box)[0])


def pad_gaps(left, right, box):
    """pad_gap of each pair of an (n, 4, 4) stack of `left` and `right` poses: an array of n gaps."""
    centres = right[:, :3, 3] - left[:, :3, 3]
    along = np.einsum('nij,ni->nj', left[:, :3, :3], centres)  # the centres' line along each pad axis
    k = np.argmax(np.abs(along), axis=1)
    return np.abs(along[np.arange(len(k)), k]) - np.asarray(box, dtype=float)[k]


class GripperKinematics(object):
    """Gap between the finger pads as a function of ``finger_joint`` and back.

    ``opening(angle)`` is the distance between the two pads' inner (facing)
    surfaces, measured along the pad normal: the pad frames' centre distance
    projected on the normal, less half a pad thickness on each side (the
    thickness is the pad box's extent along that normal, 0.0075 m in both
    upstream macros). ``angle(opening)`` inverts it by linear interpolation
    in a table of `samples` angles over the joint's limits: cheap enough for a
    node that converts at every publish, and with the default 4001 samples
    within 1e-6 rad of the exact inverse, because the gap is a smooth function
    of the angle (test_sim_models checks the round trip).

    The joint's lower limit (0.0 rad) is fully open, the upper (0.7 rad)
    closed, and the gap shrinks monotonically in between (checked on
    construction).

    Model versus the real gripper
    -----------------------------
    With the jr-robotics (Noetic) 2F-140 macro the pads' inner faces are
    about 0.1285 m apart when open and touch (-0.2 mm, a hair of overlap) at
    0.7 rad: the model's open width is about 11.5 mm short of the nominal
    0.140 m stroke of the real 2F-140 (whose fingertips are 140 mm apart fully
    open). ``min_opening`` / ``max_opening`` give the values for the model
    at hand.

    Registers to the model
    ----------------------
    The gripper's position register is turned into an opening by
    RegisterScale (the real stroke, 0..0.140 m) and the opening into an angle
    here, through these kinematics: a pad gap the model can show is shown
    exactly; a wider one (the model's last 11.5 mm) shows as fully open.
    """

    def __init__(self, urdf_text, prefix='', samples=4001):
        self.model = kinematics.Model(urdf_text)
        self.joint_name = prefix + FINGER_JOINT
        if self.joint_name not in self.model.joints:
            raise ValueError("the model has no joint '%s'" % self.joint_name)
        joint = self.model.joints[self.joint_name]
        limit = joint.limit
        if limit is None or limit.lower is None or limit.upper is None or not limit.upper > limit.lower:
            raise ValueError("joint '%s' has no usable <limit>" % self.joint_name)
        self.lower, self.upper = limit.lower, limit.upper
        base = joint.parent
        self._chains = []
        for pad in PADS:
            if prefix + pad not in self.model.robot.link_map:
                raise ValueError("the model has no link '%s'" % (prefix + pad))
            self._chains.append(self.model.chain(base, prefix + pad))
        box = _pad_box(self.model.robot.link_map[prefix + PADS[0]])
        self.pad_thickness = tuple(box) if box else (0.0, 0.0, 0.0)
        self.angles = np.linspace(self.lower, self.upper, int(samples))
        # The whole table at once: thousands of chains, one stack of matrices each pad.
        left, right = (self.model.chain_transforms(chain, {self.joint_name: self.angles}) for chain in self._chains)
        self.openings = pad_gaps(left, right, self.pad_thickness)
        if not np.all(np.diff(self.openings) < 0):
            raise ValueError('the pad gap of the model does not shrink monotonically '
                             'as %s goes from %g to %g' % (self.joint_name, self.lower, self.upper))

    # -- forward kinematics --------------------------------------------------

    def pad_poses(self, angle):
        """Poses (4x4) of the left and right pads in the gripper base frame."""
        positions = {self.joint_name: angle}
        return tuple(self.model.chain_transform(chain, positions) for chain in self._chains)

    def opening_exact(self, angle):
        """Gap between the pads' inner faces at `angle`, from forward kinematics."""
        left, right = self.pad_poses(angle)
        return pad_gap(left, right, self.pad_thickness)

    # -- public mapping ------------------------------------------------------

    @property
    def max_opening(self):
        """Gap when fully open (angle = lower limit)."""
        return float(self.openings[0])

    @property
    def min_opening(self):
        """Gap when fully closed (angle = upper limit); may be slightly negative."""
        return float(self.openings[-1])

    def opening(self, angle):
        """Pad gap (m) at finger_joint `angle` (rad), clamped to the joint limits."""
        return self.opening_exact(min(max(float(angle), self.lower), self.upper))

    def angle(self, opening):
        """finger_joint angle (rad) giving pad gap `opening` (m), clamped to the model's range."""
        # np.interp needs increasing x: the openings decrease along the table.
        return float(np.interp(-float(opening), -self.openings, self.angles))
