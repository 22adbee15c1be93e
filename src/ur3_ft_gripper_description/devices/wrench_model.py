"""What a still FT 300 reads: the weight of its tool-side load (no ROS imports).

Conventions
-----------
* A wrench is (fx, fy, fz, tx, ty, tz) in the sensor frame
  (``robotiq_ft_frame_id``: z out of the tool flange).
* The reading is the load's weight as it acts on the sensor: with the sensor
  z axis pointing straight down, a hanging mass pulls along +z, so
  ``force = m * g * (unit gravity direction in the sensor frame)`` and
  ``torque = com x force`` (moment about the sensor origin).
* Gravity points along -z of a world frame; with R the sensor's orientation
  in that frame, its direction in the sensor frame is ``R.T @ (0, 0, -1)``,
  minus R's last row.
"""

import dataclasses
import math

import numpy as np
import yaml

from ..model.inertials import combine_masses
from .. import yaml_data

STANDARD_GRAVITY = 9.80665  # m/s^2 (CGPM 1901 conventional value)


def _vec3(value, what):
    v = np.asarray(value, dtype=float).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError('%s must be 3 finite numbers, got %r' % (what, value))
    return v


@dataclasses.dataclass
class Load(object):
    """Mass (kg) and centre of mass (m, sensor frame) of what hangs on the sensor's tool side."""

    mass: float
    com: np.ndarray

    def __post_init__(self):
        self.mass = float(self.mass)
        if not np.isfinite(self.mass) or self.mass < 0:
            raise ValueError('a load\'s mass must be a finite number >= 0, got %r' % self.mass)
        self.com = _vec3(self.com, 'centre of mass')

    def with_object(self, object_mass, object_com):
        """This load plus a held object of `object_mass` at `object_com`."""
        return Load(*combine_masses([(self.mass, self.com), (object_mass, object_com)]))


@dataclasses.dataclass
class SensorSpec(object):
    """The FT 300's own figures: sensor frame, noise, the unit's offset, stream rate, and the identity it reports."""

    frame_id: str = 'robotiq_ft_frame_id'
    noise_force: float = 0.0
    noise_torque: float = 0.0
    unit_offset: tuple = (0.0,) * 6
    rate: float = 100.0
    identity: dict = dataclasses.field(default_factory=dict)


def load_sensor_spec(path):
    """The `sensor` section of a YAML file like config/sim_devices.yaml."""
    with open(path) as f:
        data = yaml_data.load(f) or {}
    if not isinstance(data, dict) or not isinstance(data.get('sensor'), dict):
        raise ValueError("%s: no 'sensor' section" % path)
    sensor = data['sensor']
    return SensorSpec(frame_id=sensor.get('frame_id', 'robotiq_ft_frame_id'),
                      noise_force=float(sensor.get('noise_force', 0.0)),
                      noise_torque=float(sensor.get('noise_torque', 0.0)),
                      unit_offset=tuple(float(v) for v in sensor.get('unit_offset', (0.0,) * 6)),
                      rate=float(sensor.get('rate', 100.0)),
                      identity={key: str(sensor.get(key, 'UNKNOWN')) for key in
                                ('serial_number', 'firmware_version', 'production_year')})


def gravity_direction(x, y, z, w):
    """The unit direction of gravity (world -z) in the frame of orientation (x, y, z, w), a unit quaternion
    in the world: minus the rotation matrix's last row."""
    return 2.0 * (y * w - x * z), -2.0 * (y * z + x * w), 2.0 * (x * x + y * y) - 1.0


def gravity_wrench(gx, gy, gz, mass, com, g=STANDARD_GRAVITY):
    """(fx, fy, fz, tx, ty, tz) that a load of `mass` at `com` puts on the sensor at rest.

    (gx, gy, gz) is the direction of gravity in the sensor frame (any length).
    Plain floats: the simulated sensor calls this 100 to 1000 times a second,
    and numpy's call overhead on 3-vectors cost more than the arithmetic.
    """
    norm = math.sqrt(gx * gx + gy * gy + gz * gz)
    if not math.isfinite(norm) or norm == 0.0:
        raise ValueError('gravity direction is zero or not finite: %r' % ((gx, gy, gz),))
    scale = float(mass) * g / norm
    fx, fy, fz = scale * gx, scale * gy, scale * gz
    cx, cy, cz = com
    return (fx, fy, fz, cy * fz - cz * fy, cz * fx - cx * fz, cx * fy - cy * fx)
