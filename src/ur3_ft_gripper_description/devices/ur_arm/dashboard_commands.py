"""The Dashboard Server's commands as config/ur_dashboard.yaml lists them, without ROS.

Which commands a controller answers depends on its generation and software
version; a line is matched to the longest command its words begin with, in
any case, and the rest of the line is the command's argument.
"""

from ..sim_params import PackageFile
from ... import yaml_data

TABLE_FILE = PackageFile('config/ur_dashboard.yaml')


def _version(text):
    return tuple(int(part) for part in str(text).split('.'))


class DashboardCommands(object):
    """The table: each command's first version per generation, its fixed reply, and the named values."""

    def __init__(self, table):
        self.entries = table['commands']
        self.user_roles = tuple(table['user_roles'])
        self.operational_modes = tuple(table['operational_modes'])
        self.flight_report_types = tuple(table['flight_report_types'])
        self._by_length = sorted(self.entries, key=lambda key: -len(key.split()))

    def match(self, line):
        """(command, argument) of a line as a client sends it, or (None, '') for no command of the table."""
        words = line.split()
        lowered = [word.lower() for word in words]
        for key in self._by_length:
            length = len(key.split())
            if lowered[:length] == key.split():
                argument = line.strip().split(None, length)[length] if len(words) > length else ''
                return key, argument.strip()
        return None, ''

    def answered(self, key, software):
        """Whether the controller `software` (a software.ControllerSoftware) answers command `key`."""
        since = self.entries[key].get(software.generation)
        return since is not None and tuple(software.version) >= _version(since)

    def reply(self, key):
        return self.entries[key].get('reply')


_CACHE = {}


def read(path=None):
    """The DashboardCommands of the table at `path` (default: the package's), read once per path."""
    path = path or TABLE_FILE.path()
    if path not in _CACHE:
        with open(path) as stream:
            _CACHE[path] = DashboardCommands(yaml_data.load(stream))
    return _CACHE[path]
