"""What a still FT 300 reads: the weight of its tool-side load, plus a zero offset.

Pure numpy (no ROS imports), so the simulated sensor node and the unit tests
share one implementation.

Conventions
-----------
* A wrench is a pair ``(force, torque)`` of numpy arrays of shape (3,), in
  the sensor frame (``robotiq_ft_frame_id``: z out of the tool flange).
* The reading is the load's weight as it acts on the sensor: with the sensor
  z axis pointing straight down, a hanging mass pulls along +z, so
  ``force = m * g * (unit gravity direction in the sensor frame)`` and
  ``torque = com x force`` (moment about the sensor origin).
* Orientation: ``sensor_orientation`` is the rotation of the sensor frame in
  a world frame whose z axis points up (the 3x3 rotation part of
  tf2 ``lookup_transform(world, sensor)``, or of
  ``kinematics.Model.transform(world, sensor)``). Gravity points along world
  -z, so in the sensor frame it is ``R.T @ (0, 0, -1)``.
"""

import dataclasses

import numpy as np
import yaml

STANDARD_GRAVITY = 9.80665  # m/s^2 (CGPM 1901 conventional value)


def _vec3(value, what):
    v = np.asarray(value, dtype=float).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError('%s must be 3 finite numbers, got %r' % (what, value))
    return v


@dataclasses.dataclass
class Payload(object):
    """Mass (kg) and centre of mass (m, sensor frame) of the tool-side load,
    with the sensor figures used to simulate it."""

    mass: float
    com: np.ndarray
    frame_id: str = 'robotiq_ft_frame_id'
    noise_force: float = 0.0
    noise_torque: float = 0.0
    rate: float = 100.0

    def __post_init__(self):
        self.mass = float(self.mass)
        if not np.isfinite(self.mass) or self.mass < 0:
            raise ValueError('payload mass must be a finite number >= 0, got %r' % self.mass)
        self.com = _vec3(self.com, 'payload com')

    def combined(self, object_mass, object_com):
        """(mass, com) of this load plus a held object of `object_mass` at `object_com`."""
        return combine_masses([(self.mass, self.com), (object_mass, object_com)])

    def with_object(self, object_mass, object_com):
        """A copy of this payload that also carries a held object."""
        mass, com = self.combined(object_mass, object_com)
        return dataclasses.replace(self, mass=mass, com=com)


def combine_masses(parts):
    """Total mass and common centre of mass of [(mass, com), ...]."""
    total = 0.0
    moment = np.zeros(3)
    for mass, com in parts:
        mass = float(mass)
        if not np.isfinite(mass) or mass < 0:
            raise ValueError('a mass must be a finite number >= 0, got %r' % mass)
        total += mass
        moment += mass * _vec3(com, 'centre of mass')
    if total == 0.0:
        return 0.0, np.zeros(3)
    return total, moment / total


def load_payload(path):
    """Payload from a YAML file like config/sim_devices.yaml."""
    with open(path) as f:
        data = yaml.safe_load(f) or {}
    if not isinstance(data, dict) or not isinstance(data.get('payload'), dict):
        raise ValueError("%s: no 'payload' section (with mass and com)" % path)
    payload, sensor = data['payload'], data.get('sensor') or {}
    missing = [k for k in ('mass', 'com') if k not in payload]
    if missing:
        raise ValueError("%s: 'payload' has no %s" % (path, ' or '.join(missing)))
    return Payload(mass=payload['mass'], com=payload['com'],
                   frame_id=payload.get('frame_id', 'robotiq_ft_frame_id'),
                   noise_force=float(sensor.get('noise_force', 0.0)),
                   noise_torque=float(sensor.get('noise_torque', 0.0)),
                   rate=float(sensor.get('rate', 100.0)))


def gravity_direction(gravity):
    """Unit gravity direction in the sensor frame.

    `gravity` is either the 3x3 sensor orientation in a z-up world frame (see
    the module docstring) or a 3-vector already in the sensor frame (only its
    direction is used).
    """
    g = np.asarray(gravity, dtype=float)
    if g.shape == (3, 3):
        direction = g.T.dot([0.0, 0.0, -1.0])
    elif g.reshape(-1).shape == (3,):
        direction = g.reshape(-1)
    else:
        raise ValueError('gravity must be a 3x3 rotation or a 3-vector, got shape %s' % (g.shape,))
    norm = np.linalg.norm(direction)
    if not np.isfinite(norm) or norm == 0.0:
        raise ValueError('gravity direction is zero or not finite: %r' % (direction,))
    return direction / norm


def gravity_wrench(gravity, mass, com, g=STANDARD_GRAVITY):
    """(force, torque) that a load of `mass` at `com` puts on the sensor at rest."""
    force = float(mass) * float(g) * gravity_direction(gravity)
    torque = np.cross(_vec3(com, 'com'), force)
    return force, torque


def add_noise(wrench, noise_force, noise_torque, rng=None):
    """`wrench` plus white Gaussian noise of the given standard deviations."""
    rng = rng if rng is not None else np.random.default_rng()
    force, torque = wrench
    return (np.asarray(force, dtype=float) + rng.normal(0.0, noise_force, 3),
            np.asarray(torque, dtype=float) + rng.normal(0.0, noise_torque, 3))


class ZeroOffset(object):
    """The sensor's "zero" (bias) command: remember a wrench and subtract it."""

    def __init__(self):
        self.clear()

    def set(self, wrench):
        force, torque = wrench
        self.force = _vec3(force, 'offset force').copy()
        self.torque = _vec3(torque, 'offset torque').copy()

    def clear(self):
        self.force = np.zeros(3)
        self.torque = np.zeros(3)

    @property
    def is_set(self):
        return bool(np.any(self.force) or np.any(self.torque))

    def apply(self, wrench):
        force, torque = wrench
        return (_vec3(force, 'force') - self.force, _vec3(torque, 'torque') - self.torque)
