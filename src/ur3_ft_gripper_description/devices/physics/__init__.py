"""The simulated cell on physics (MuJoCo): the engine and its host, importing nothing of the arm's.

* ``world``: the world file (a table and objects), checked field by field;
* ``cell``: ``Cell``, one MuJoCo model of export_mjcf's robot and a world,
  stepped in whole timesteps: the arm's servos, the FT 300's reading, the
  finger drive, the objects, the protective stop;
* ``arm_cell``: the arm node's Cell, of robot_description as loaded and ~world_file;
* ``link``: the private socket through which the FT 300 and 2F-140 nodes read the cell;
* ``pacing``: the real-time factor the arm's node reports.

MuJoCo is optional: only this package imports it, and only when a Cell is
made; without it, ``require_mujoco`` raises ``MissingMuJoCo``, whose message
is one line with the install command.
"""

INSTALL = 'pip install mujoco (rosdep key python3-mujoco-pip)'


class MissingMuJoCo(ImportError):
    """MuJoCo is not installed; the message is one line with the install command."""


def require_mujoco():
    """The mujoco module, or MissingMuJoCo naming the install command."""
    try:
        import mujoco
    except ImportError as exc:
        raise MissingMuJoCo('physics needs MuJoCo, which does not import here (%s): %s'
                            % (exc, INSTALL)) from None
    return mujoco
