"""The arm node's physics cell: the model as loaded in robot_description, in the world of ~world_file.

With ``~physics`` true, the simulated arm's node (``ur_hardware_interface``)
builds one Cell and steps it with its control loop; the FT 300 and 2F-140
nodes reach it through the link (``link.py``). Reading the parameters here
keeps the node an adapter.

The arm's node declares these two private parameters with its others
(ur_arm/settings.py's PARAMETERS; their reference: doc/node_parameters.md).
"""

from .. import sim_params
from .world import load_world

DEFAULT_WORLD = sim_params.PackageFile('config/worlds/default.yaml')


def default_world_file():
    return DEFAULT_WORLD.path()


def world_file(name, value):
    """The check of ~world_file: a path; empty means the default world."""
    path = value or default_world_file()
    if not isinstance(path, str):
        raise sim_params.ParamError('%s=%r must be the path of a world file' % (name, path))
    return path


PARAMETERS = (
    sim_params.Param('~physics', False, 'true: the joints move on MuJoCo (PyPI mujoco), in the world of '
                     '~world_file, and the node serves the physics cell to the FT 300 and 2F-140 nodes '
                     '(sim_devices.launch physics:=true); false: kinematically, no MuJoCo needed', sim_params.flag),
    sim_params.Param('~world_file', DEFAULT_WORLD, 'With ~physics: the world file, a table and objects in the '
                     "robot's base frame (format: doc/simulation.md); empty: the default", world_file),
)


def cell_for_arm(get_param, settings):
    """The Cell of robot_description (the user's calibration, ur_type and prefix as loaded) in ~world_file,
    the arm at its start pose. MissingMuJoCo, WorldError or ParamError: one line each."""
    from . import require_mujoco
    from .cell import Cell
    require_mujoco()  # before the world and the model: the line a user without MuJoCo needs first
    world = load_world(sim_params.read(get_param, PARAMETERS, '~world_file'))
    return Cell.from_description(get_param('robot_description', None), settings.ur_type, settings.prefix, world,
                                 settings.initial)
