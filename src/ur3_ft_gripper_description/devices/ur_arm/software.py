"""The controller software a UR model runs, from config/ur_software.yaml, without ROS.

That file is the one home of each model's software version; everything that
depends on the controller generation is derived here from the major version,
as ur_robot_driver derives it (major < 5: CB3, else e-Series).
"""

import os

import yaml

from .. import sim_params

CB3, E_SERIES = 'CB3', 'e-Series'


class UnknownModel(ValueError):
    """A ur_type the table does not list; the message is one line naming the known ones."""


def default_table_file():
    return os.path.join(sim_params.package_path(), 'config', 'ur_software.yaml')


def read_table(path=None):
    """{ur_type: (major, minor, bugfix, build)} of the table at `path` (default: the package's)."""
    path = path or default_table_file()
    with open(path) as stream:
        data = yaml.safe_load(stream)
    return {name: tuple(int(v) for v in entry['software_version']) for name, entry in data.items()}


class ControllerSoftware(object):
    """The software of one model's controller and what the simulated arm derives from it."""

    def __init__(self, ur_type, version):
        self.ur_type = ur_type
        self.version = tuple(version)

    @property
    def generation(self):
        return CB3 if self.version[0] < 5 else E_SERIES

    @property
    def e_series(self):
        return self.generation == E_SERIES

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
    table = read_table(path)
    if ur_type not in table:
        raise UnknownModel('%r is not a UR model the simulated arm knows; it knows %s (config/ur_software.yaml '
                           'lists each with its controller software)' % (ur_type, ', '.join(sorted(table, key=_order))))
    return ControllerSoftware(ur_type, table[ur_type])


def _order(name):
    digits = ''.join(c for c in name if c.isdigit())
    return (int(digits or 0), name)
