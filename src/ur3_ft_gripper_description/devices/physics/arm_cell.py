"""The arm node's physics cell: the model as loaded in robot_description, in the world of ~world_file.

With ``~physics`` true, the simulated arm's node (``ur_hardware_interface``)
builds one Cell and steps it with its control loop; the FT 300 and 2F-140
nodes reach it through the link (``link.py``). Reading the parameters here
keeps the node an adapter.

Private parameters of the arm's node:
  ~physics     false ; true: the joints move on MuJoCo (PhysicsJointMotion), not kinematically
  ~world_file  config/worlds/default.yaml ; the table and objects (world.py describes the format)
"""

import os

from .. import sim_params
from .world import load_world


def default_world_file():
    return os.path.join(sim_params.package_path(), 'config', 'worlds', 'default.yaml')


def cell_for_arm(get_param, settings):
    """The Cell of robot_description (the user's calibration, ur_type and prefix as loaded) in ~world_file,
    the arm at its start pose. MissingMuJoCo, WorldError or ParamError: one line each."""
    from . import require_mujoco
    from .cell import Cell
    require_mujoco()  # before the world and the model: the line a user without MuJoCo needs first
    path = get_param('~world_file', '') or default_world_file()
    if not isinstance(path, str):
        raise sim_params.ParamError('~world_file=%r must be the path of a world file' % (path,))
    world = load_world(path)
    return Cell.from_description(get_param('robot_description', None), settings.ur_type, settings.prefix, world,
                                 settings.initial)
