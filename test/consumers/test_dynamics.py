"""Masses and gravity torques as pinocchio and PyBullet read the exported URDF."""
import xml.etree.ElementTree as ElementTree

import numpy as np
import pinocchio
import pybullet
import pytest

from conftest import ARM_JOINTS, FRAMES_TOLERANCE, ROBOTIQ, expected_total_mass, exported_urdf


def pinocchio_model(options):
    return pinocchio.buildModelFromUrdf(exported_urdf(*options), mimic=True)


@pytest.fixture
def bullet():
    client = pybullet.connect(pybullet.DIRECT)
    yield client
    pybullet.disconnect(client)


def load_in_bullet(client, options):
    body = pybullet.loadURDF(exported_urdf(*options), useFixedBase=True,
                             flags=pybullet.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client)
    assert body >= 0
    return body


def bullet_links(client, body):
    """{link name: mass} of every non-root link, as PyBullet holds it."""
    return {pybullet.getJointInfo(body, j, physicsClientId=client)[12].decode():
            pybullet.getDynamicsInfo(body, j, physicsClientId=client)[0]
            for j in range(pybullet.getNumJoints(body, physicsClientId=client))}


def test_pinocchio_total_mass_is_the_arm_plus_the_manuals_parts(options):
    model = pinocchio_model(options)
    total = sum(inertia.mass for inertia in model.inertias)
    assert total == pytest.approx(expected_total_mass(options), abs=FRAMES_TOLERANCE)


def tool_load(options):
    """(mass, centre of mass in tool0) of everything beyond the flange, by pinocchio.

    pinocchio lumps the fixed links onto wrist_3_joint's body: its subtree's
    mass and centre of mass, minus wrist_3_link's own inertial (from the URDF).
    """
    path = exported_urdf(*options)
    model = pinocchio_model(options)
    data = model.createData()
    pinocchio.centerOfMass(model, data, pinocchio.neutral(model), True)
    pinocchio.updateFramePlacements(model, data)
    joint = model.getJointId('wrist_3_joint')
    inertial = ElementTree.parse(path).getroot().find("link[@name='wrist_3_link']/inertial")
    wrist_mass = float(inertial.find('mass').get('value'))
    wrist_com = data.oMf[model.getFrameId('wrist_3_link', pinocchio.FrameType.BODY)].act(
        np.array([float(v) for v in inertial.find('origin').get('xyz').split()]))
    subtree_com = data.oMi[joint].act(data.com[joint])  # pinocchio gives it in the joint's frame
    mass = data.mass[joint] - wrist_mass
    com = (data.mass[joint] * subtree_com - wrist_mass * wrist_com) / mass
    return mass, data.oMf[model.getFrameId('tool0', pinocchio.FrameType.BODY)].actInv(com)


@pytest.mark.parametrize('options, figures', [(['--no-gripper'], 'ft300'), ([], 'ft300_with_2f140')])
def test_pinocchio_sees_the_manuals_mass_and_centre_of_mass_beyond_the_flange(options, figures):
    mass, com = tool_load(options)
    assert mass == pytest.approx(ROBOTIQ[figures]['mass'], abs=FRAMES_TOLERANCE)
    assert com[2] == pytest.approx(ROBOTIQ[figures]['com_z_from_tool0'], abs=1e-4)
    assert np.hypot(com[0], com[1]) < 5e-4


def test_pybullet_holds_the_models_mass_on_every_link(bullet, options):
    body = load_in_bullet(bullet, options)
    urdf = ElementTree.parse(exported_urdf(*options)).getroot()
    given = {link.get('name'): float(link.find('inertial/mass').get('value'))
             for link in urdf.findall('link') if link.find('inertial') is not None}
    held = {}
    for j in range(pybullet.getNumJoints(body, physicsClientId=bullet)):
        name = pybullet.getJointInfo(body, j, physicsClientId=bullet)[12].decode()
        held[name] = pybullet.getDynamicsInfo(body, j, physicsClientId=bullet)[0]
    # Every link but the (fixed) root is PyBullet's own link: none left to its 1 kg default.
    assert sorted(held) == sorted(given)
    for name, mass in held.items():
        assert mass == pytest.approx(given[name], abs=1e-12), name
    assert sum(held.values()) == pytest.approx(expected_total_mass(options), abs=FRAMES_TOLERANCE)


def test_gravity_torques_at_zero_agree_between_pybullet_and_pinocchio(bullet, options):
    model = pinocchio_model(options)
    data = model.createData()
    tau = pinocchio.computeGeneralizedGravity(model, data, pinocchio.neutral(model))
    expected = [tau[model.joints[model.getJointId(name)].idx_v] for name in ARM_JOINTS]

    body = load_in_bullet(bullet, options)
    pybullet.setGravity(0, 0, -9.81, physicsClientId=bullet)
    movable = [j for j in range(pybullet.getNumJoints(body, physicsClientId=bullet))
               if pybullet.getJointInfo(body, j, physicsClientId=bullet)[2] != pybullet.JOINT_FIXED]
    zero = [0.0] * len(movable)
    torques = pybullet.calculateInverseDynamics(body, zero, zero, zero, physicsClientId=bullet)
    names = [pybullet.getJointInfo(body, j, physicsClientId=bullet)[1].decode() for j in movable]
    got = [torques[names.index(name)] for name in ARM_JOINTS]
    assert np.allclose(got, expected, rtol=0.01, atol=1e-4), (got, expected)
    # The arm carries the tool: the shoulder torque is the whole arm's, not a phantom's.
    assert abs(expected[1]) > 10

