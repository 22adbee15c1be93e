"""Checked private parameters for the simulated-device nodes.

A bad value stops the node with one line naming the parameter, the value and
what would be accepted, instead of a traceback from deep inside the loop.
The readers take a ``get_param(name, default)`` callable (``rospy.get_param``
in the nodes, a dict lookup in the tests), so they need no ROS master.
"""

import math
import os

import rospkg

PACKAGE = 'ur3_ft_gripper_description'


class ParamError(ValueError):
    """A private parameter has a value the node cannot use."""


def package_path():
    return rospkg.RosPack().get_path(PACKAGE)


def default_devices_file():
    return os.path.join(package_path(), 'config', 'sim_devices.yaml')


def number(get_param, name, default, minimum=None, strictly_above=None):
    """A finite float parameter, optionally bounded below."""
    value = get_param(name, default)
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


def vector3(get_param, name, default):
    """Three finite floats, given as a list or as a string like '0 0 0.1' or '[0, 0, 0.1]'."""
    value = get_param(name, default)
    items = value
    if isinstance(value, str):
        items = value.replace('[', ' ').replace(']', ' ').replace(',', ' ').split()
    try:
        result = [float(v) for v in items]
    except (TypeError, ValueError):
        raise ParamError('%s=%r must be three numbers (x, y, z)' % (name, value))
    if len(result) != 3 or not all(math.isfinite(v) for v in result):
        raise ParamError('%s=%r must be three finite numbers (x, y, z)' % (name, value))
    return result


def frame(get_param, name, default):
    """A TF frame name: not empty, no leading slash (tf2 rejects those)."""
    value = get_param(name, default)
    if not isinstance(value, str) or not value.strip():
        raise ParamError('%s=%r must be a TF frame name' % (name, value))
    if value.startswith('/'):
        raise ParamError("%s=%r: tf2 frame names have no leading '/'; use %r" % (
            name, value, value.lstrip('/')))
    return value


def existing_file(get_param, name, default):
    path = get_param(name, default)
    if not isinstance(path, str) or not os.path.isfile(path):
        raise ParamError('%s=%r: no such file' % (name, path))
    return path


def prefix(get_param):
    """~prefix: the model's link/joint prefix, '' by default."""
    value = get_param('~prefix', '')
    if not isinstance(value, str):
        raise ParamError('~prefix=%r must be a string' % (value,))
    return value


def from_devices_file(get_param, load):
    """`load(path)` of ~devices_file (default config/sim_devices.yaml), its errors as ParamError."""
    path = existing_file(get_param, '~devices_file', default_devices_file())
    try:
        return load(path)
    except (OSError, ValueError) as exc:
        raise ParamError('~devices_file: %s' % exc)
