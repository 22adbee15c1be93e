"""The physics cell against known truths: a mass's weight, an object's width, a contact's force.

These tests need MuJoCo (PyPI: mujoco 4.0.0 on Python 3.11, 3.2.3 on 3.8). Without it every test
that needs it fails with the cell's one line naming the install command; none is skipped.

The robot is the package's default model (UR3 + FT 300 + 2F-140), expanded and exported once
per session; each test builds its own Cell from that file and a world written for it. What the
tests import by name (START, TABLE, Arm, close_on...) is in ur3_ft_gripper_testing.physics.
"""
import os
import shutil
import tempfile

import pytest

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices.physics import MissingMuJoCo, require_mujoco
from ur3_ft_gripper_description.devices.physics.world import load_world
from ur3_ft_gripper_description.model import description, export, mjcf
from ur3_ft_gripper_description.number_text import number, number_list
from ur3_ft_gripper_testing.physics import ARM_JOINTS, START, TABLE
# test_cell.py and test_link.py still take these from here, while their move to
# ur3_ft_gripper_testing.physics is pending; with test/unit in the same session this works
# only while this conftest is the last one pytest imports (test/physics named after test/unit).
from ur3_ft_gripper_testing.physics import STANDARD_GRAVITY, Arm, Served, close_on  # noqa: F401


@pytest.fixture(scope='session')
def mujoco():
    try:
        return require_mujoco()
    except MissingMuJoCo as exc:
        missing = str(exc)
    pytest.fail(missing, pytrace=False)  # outside the except: the one line, without the ImportError's story


@pytest.fixture(scope='session')
def robot():
    """(MJCF path, URDF text) of the default model, exported once."""
    folder = tempfile.mkdtemp(prefix='ur3_ft_gripper_physics_')
    mappings = export.model_mappings()
    doc = description.expand_model(mappings)
    path = os.path.join(folder, 'robot.xml')
    mjcf.write_mjcf(doc, mappings, path)
    yield path, description.to_xml(doc)
    shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture
def make_cell(mujoco, robot, tmp_path):
    """make_cell(world text, initial arm) -> a Cell of the default model in that world."""
    from ur3_ft_gripper_description.devices.physics.cell import Cell

    def make(world_text=TABLE, initial_arm=START):
        path = tmp_path / 'world.yaml'
        path.write_text(world_text)
        return Cell(robot[0], robot[1], load_world(str(path)), initial_arm=initial_arm)
    return make


@pytest.fixture(scope='session')
def pad_centre(robot):
    """(x, y) of the pads' centre line in the start pose (base_link): the model's gripper_tcp."""
    model = kinematics.Model(robot[1])
    positions = dict(zip(ARM_JOINTS, START))
    return tuple(model.transform(model.root(), 'gripper_tcp', positions)[:2, 3])


@pytest.fixture
def between_pads(pad_centre):
    """between_pads(width, ...) -> a world with an object standing on the table between the open pads."""
    def world(width, height=0.12, mass=1.0, depth=0.06, shape='box', quat_yaw=0.0, mesh=None):
        if shape == 'box':
            size = 'size: [%s]' % number_list((depth, width, height))
        elif shape == 'cylinder':
            size = 'size: [%s]' % number_list((width, height))
        else:
            size = 'mesh: %s' % mesh
        z = height / 2.0 if shape != 'mesh' else 0.0
        return TABLE + """
objects:
  - name: held
    shape: %s
    %s
    pose: [%s, 0, 0, %s]
    mass: %s
    friction: 0.5
""" % (shape, size, number_list((pad_centre[0], pad_centre[1], z)), number(quat_yaw), number(mass))
    return world
