"""The simulated-device nodes' private parameters: declared once per node, read and checked through here.

Each node module declares its private parameters in one table, ``PARAMETERS``:
a sequence of Param (name, default, doc, check). The node reads them only
with ``read(get_param, PARAMETERS, name)``, so the table is where their
defaults live and doc/node_parameters.md is generated from it
(tools/generate_references.py). Reading a name the table does not declare is
a bug in the node, not bad input: ParamDeclarationError.

A bad value stops the node with one line naming the parameter, the value and
what would be accepted (ParamError), instead of a traceback from deep inside
the loop. ``get_param(name, default)`` is ``rospy.get_param`` in the nodes and
a dict lookup in the tests, so nothing here needs a ROS master.
"""

import collections
import math
import os

from ..model.names import shared_rospack

PACKAGE = 'ur3_ft_gripper_description'


class ParamError(ValueError):
    """A private parameter has a value the node cannot use."""


class ParamDeclarationError(LookupError):
    """A node reads a parameter otherwise than its PARAMETERS table declares it: a bug in the node."""


class Param(collections.namedtuple('Param', 'name default doc check')):
    """A node's private parameter: its name ('~rate'), its default (None: unset), what it means (for the
    reference page), and check(name, value) -> the value to use, or ParamError (None: the value as given).

    A default that is only known when the node starts (a figure of another
    file, another parameter) is a StartupDefault; one inside this package a
    PackageFile.
    """

    def __new__(cls, name, default, doc, check=None):
        return super(Param, cls).__new__(cls, name, default, doc, check)


class StartupDefault(collections.namedtuple('StartupDefault', 'shown')):
    """A default the node works out when it starts; `shown` tells users how (markdown for the reference).
    The node passes the value: read(..., default=value)."""


class PackageFile(collections.namedtuple('PackageFile', 'relative')):
    """A default file inside this package, found with rospkg when it is read."""

    def path(self):
        return os.path.join(package_path(), self.relative)

    @property
    def shown(self):
        return '`%s` of this package' % self.relative


_GIVEN_BY_THE_TABLE = object()


def read(get_param, table, name, default=_GIVEN_BY_THE_TABLE):
    """The value of `name` as `table` declares it: its default when unset, through its check.

    `default` is given exactly when the declared default is a StartupDefault.
    """
    declared = [param for param in table if param.name == name]
    if not declared:
        raise ParamDeclarationError('%s is read but not declared: add a Param for it to the node\'s PARAMETERS'
                                    % name)
    param = declared[0]
    at_startup = isinstance(param.default, StartupDefault)
    if at_startup != (default is not _GIVEN_BY_THE_TABLE):
        raise ParamDeclarationError('%s: %s' % (name, 'its StartupDefault needs the value: read(..., default=)'
                                                if at_startup else 'its default is the table\'s, not the reader\'s'))
    if not at_startup:
        default = param.default.path() if isinstance(param.default, PackageFile) else param.default
    value = get_param(name, default)
    return param.check(name, value) if param.check else value


# -- checks: check(name, value) -> value, or ParamError --------------------------------------------------

def number(minimum=None, strictly_above=None):
    """The check of a finite float, optionally bounded below."""
    def check(name, value):
        try:
            result = float(value)
        except (TypeError, ValueError):
            raise ParamError('%s=%r is not a number' % (name, value))
        if not math.isfinite(result):
            raise ParamError('%s=%r must be a finite number' % (name, value))
        if minimum is not None and result < minimum:
            raise ParamError('%s=%r must be >= %g' % (name, value, minimum))
        if strictly_above is not None and result <= strictly_above:
            raise ParamError('%s=%r must be > %g' % (name, value, strictly_above))
        return result
    return check


def unset_or(check):
    """`check`, but None (the parameter is not set) passes as None."""
    return lambda name, value: None if value is None else check(name, value)


def _finite_numbers(name, value, what):
    """len(what) finite floats, given as a list or as a string like '0 0 0.1' or '[0, 0, 0.1]'."""
    items = value
    if isinstance(value, str):
        items = value.replace('[', ' ').replace(']', ' ').replace(',', ' ').split()
    try:
        result = [float(v) for v in items]
    except (TypeError, ValueError):
        result = None
    if result is None or len(result) != len(what) or not all(math.isfinite(v) for v in result):
        raise ParamError('%s=%r must be %d finite numbers (%s)' % (name, value, len(what), ', '.join(what)))
    return result


def vector3(name, value):
    """Three finite floats, given as a list or as a string like '0 0 0.1' or '[0, 0, 0.1]'."""
    return _finite_numbers(name, value, ('x', 'y', 'z'))


def wrench(name, value):
    """Six finite floats (fx fy fz in N, tx ty tz in N m), as a list or a string like vector3's."""
    return _finite_numbers(name, value, ('fx', 'fy', 'fz', 'tx', 'ty', 'tz'))


def frame(name, value):
    """A TF frame name: not empty, no leading slash (tf2 rejects those)."""
    if not isinstance(value, str) or not value.strip():
        raise ParamError('%s=%r must be a TF frame name' % (name, value))
    if value.startswith('/'):
        raise ParamError("%s=%r: tf2 frame names have no leading '/'; use %r" % (
            name, value, value.lstrip('/')))
    return value


def existing_file(name, value):
    if not isinstance(value, str) or not os.path.isfile(value):
        raise ParamError('%s=%r: no such file' % (name, value))
    return value


def string(name, value):
    if not isinstance(value, str):
        raise ParamError('%s=%r must be a string' % (name, value))
    return value


def flag(name, value):
    """On or off, as Python reads the value (roslaunch sets true/false as booleans)."""
    return bool(value)


# -- what the device nodes share ------------------------------------------------------------------------

def package_path():
    return shared_rospack().get_path(PACKAGE)


SIM_DEVICES_FILE = PackageFile('config/sim_devices.yaml')


def default_devices_file():
    return SIM_DEVICES_FILE.path()


PREFIX = Param('~prefix', '', "Prefix of the model's links and joints, as the model was loaded with; the "
               'default frames and joints follow it', string)
DEVICES_FILE = Param('~devices_file', SIM_DEVICES_FILE, "The simulated devices' figures (the format: the "
                     'default file, which gives their sources)', existing_file)
PHYSICS = Param('~physics', False, 'true: the device is the physics cell\'s (MuJoCo), served by the simulated '
                'arm\'s node ur_hardware_interface in the same namespace (sim_arm.launch physics:=true)', flag)


def from_devices_file(get_param, table, load):
    """`load(path)` of the ~devices_file `table` declares, its errors as ParamError."""
    path = read(get_param, table, '~devices_file')
    try:
        return load(path)
    except (OSError, ValueError) as exc:
        raise ParamError('~devices_file: %s' % exc)
