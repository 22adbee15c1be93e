"""The controller software a UR model runs, from config/ur_software.yaml, without ROS.

That file is the one home of each model's software version; everything that
depends on the controller generation is derived here from the major version,
as ur_robot_driver derives it (major < 5: CB3, else e-Series).
"""

import os

from .. import sim_params
from ... import yaml_data

CB3, E_SERIES = 'CB3', 'e-Series'
# Each generation's key in the network interfaces' tables (config/rtde_variables.yaml and the others).
TABLE_KEYS = {CB3: 'cb3', E_SERIES: 'e_series'}


class UnknownModel(ValueError):
    """A ur_type the table does not list; the message is one line naming the known ones."""


def default_table_file():
    return os.path.join(sim_params.package_path(), 'config', 'ur_software.yaml')


def _read_entries(path=None):
    with open(path or default_table_file()) as stream:
        return yaml_data.load(stream)


def _version(entry):
    return tuple(int(v) for v in entry['software_version'])


def read_table(path=None):
    """{ur_type: (major, minor, bugfix, build)} of the table at `path` (default: the package's)."""
    return {name: _version(entry) for name, entry in _read_entries(path).items()}


class ControllerSoftware(object):
    """The software of one model's controller and what the simulated arm derives from it."""

    def __init__(self, ur_type, version, serial_number=''):
        self.ur_type = ur_type
        self.version = tuple(version)
        self.serial_number = serial_number

    @property
    def model_name(self):
        """The Dashboard Server's "get robot model" answer: UR and the payload class, without the e-Series' e
        (UR3 ... UR30)."""
        return 'UR' + ''.join(c for c in self.ur_type if c.isdigit())

    @property
    def generation(self):
        return CB3 if self.version[0] < 5 else E_SERIES

    @property
    def e_series(self):
        return self.generation == E_SERIES

    @property
    def table_key(self):
        """The generation's key in the network interfaces' tables."""
        return TABLE_KEYS[self.generation]

    @property
    def version_text(self):
        """major.minor.bugfix.build, as the Dashboard Server prints it (clients parse all four)."""
        return '.'.join(str(v) for v in self.version)

    def zero_ftsensor_refusal(self):
        """Why zero_ftsensor is refused (ur_robot_driver's message), or None where it is served."""
        if self.e_series:
            return None
        return ('Zeroing the Force-Torque sensor is only available for e-Series robots (Major version >= 5). '
                "This robot's version is %s" % '.'.join(str(v) for v in self.version))

    def __repr__(self):
        return 'ControllerSoftware(%r, %s %s)' % (self.ur_type, self.generation, self.version_text)


def for_model(ur_type, path=None):
    """The ControllerSoftware of `ur_type`; UnknownModel (one line) if the table does not list it."""
    entries = _read_entries(path)
    if ur_type not in entries:
        raise UnknownModel('%r is not a UR model the simulated arm knows; it knows %s (config/ur_software.yaml '
                           'lists each with its controller software)' % (ur_type, ', '.join(sorted(entries, key=_order))))
    entry = entries[ur_type]
    return ControllerSoftware(ur_type, _version(entry), str(entry['serial_number']))


def _order(name):
    digits = ''.join(c for c in name if c.isdigit())
    return (int(digits or 0), name)
