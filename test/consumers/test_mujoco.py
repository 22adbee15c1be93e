"""export_mjcf's file in MuJoCo, loaded exactly as written."""
import os
import xml.etree.ElementTree as ElementTree

import mujoco
import numpy as np
import pytest

from conftest import ARM_JOINTS, FOLDER, FRAMES_TOLERANCE, expected_total_mass, run

ARM_POSES = {  # the arm held here; names as upstream's SRDF states where they are those
    'home': [0.0] * 6,
    'up': [0.0, -1.5707, 0.0, -1.5707, 0.0, 0.0],
    'tool_down': [0.0, -1.5707, 1.5707, -1.5707, -1.5707, 0.0],
}
SETTLE_TIME = 2.0


def exported_mjcf(*options):
    path = os.path.join(FOLDER, 'mjcf%s' % ''.join(options), 'model.xml')
    if not os.path.isfile(path):
        os.makedirs(os.path.dirname(path), exist_ok=True)
        run(['rosrun', 'ur3_ft_gripper_description', 'export_mjcf', '-o', path] + list(options))
    return path


@pytest.fixture(scope='module')
def model():
    return mujoco.MjModel.from_xml_path(exported_mjcf())


def qpos_address(model, joint):
    return model.jnt_qposadr[model.joint(joint).id]


def mimic_laws(model):
    """(mimic joint, leader, offset, multiplier) of every joint equality."""
    return [(model.joint(model.eq_obj1id[i]).name, model.joint(model.eq_obj2id[i]).name,
             model.eq_data[i][0], model.eq_data[i][1])
            for i in range(model.neq) if model.eq_type[i] == mujoco.mjtEq.mjEQ_JOINT]


@pytest.mark.parametrize('options', [[], ['--no-ft-sensor'], ['--no-gripper'], ['--world']],
                         ids=['ft_sensor-gripper', 'gripper', 'ft_sensor', 'world'])
def test_total_mass_is_the_models(options):
    model = mujoco.MjModel.from_xml_path(exported_mjcf(*options))
    assert sum(model.body_mass) == pytest.approx(expected_total_mass(options), abs=FRAMES_TOLERANCE)


def test_every_mimic_joint_is_an_equality_on_finger_joint(model):
    laws = mimic_laws(model)
    assert len(laws) == 5
    assert {leader for _, leader, _, _ in laws} == {'finger_joint'}
    assert sorted(abs(multiplier) for _, _, _, multiplier in laws) == [1.0] * 5


def test_meshes_are_files_mujoco_reads(model):
    root = ElementTree.parse(exported_mjcf()).getroot()
    files = [mesh.get('file') for mesh in root.iter('mesh')]
    assert files and all(f.endswith('.stl') and os.path.isfile(f) for f in files)
    assert model.nmesh == len(files)
    assert model.ngeom >= 20  # every collision geometry of the model


def test_linkage_pins_do_not_collide(model):
    root = ElementTree.parse(exported_mjcf()).getroot()
    excluded = {tuple(sorted((e.get('body1'), e.get('body2')))) for e in root.iter('exclude')}
    assert model.nexclude == len(excluded)
    for side in ('left', 'right'):
        assert ('%s_inner_finger' % side, '%s_inner_knuckle' % side) in excluded
        assert ('%s_inner_knuckle' % side, '%s_outer_knuckle' % side) in excluded


@pytest.mark.parametrize('opening', [0.0, 0.35, 0.699], ids=['open', 'half', 'closed'])
@pytest.mark.parametrize('pose', sorted(ARM_POSES))
def test_with_the_arm_held_the_gripper_settles_on_its_linkage_law(model, pose, opening):
    data = mujoco.MjData(model)
    arm = [qpos_address(model, joint) for joint in ARM_JOINTS]
    arm_dofs = [model.jnt_dofadr[model.joint(joint).id] for joint in ARM_JOINTS]
    data.qpos[arm] = ARM_POSES[pose]
    data.qpos[qpos_address(model, 'finger_joint')] = opening
    laws = mimic_laws(model)
    for joint, leader, offset, multiplier in laws:
        data.qpos[qpos_address(model, joint)] = offset + multiplier * opening
    data.ctrl[model.actuator('finger_joint').id] = opening  # the motor holds where it is
    fingers = [model.jnt_dofadr[j] for j in range(model.njnt) if model.joint(j).name not in ARM_JOINTS]
    worst_speed, worst_drift = 0.0, 0.0
    for _ in range(int(round(SETTLE_TIME / model.opt.timestep))):
        mujoco.mj_step(model, data)
        data.qpos[arm] = ARM_POSES[pose]  # the arm is held
        data.qvel[arm_dofs] = 0.0
        worst_speed = max(worst_speed, float(np.max(np.abs(data.qvel[fingers]))))
        for joint, leader, offset, multiplier in laws:
            law = offset + multiplier * data.qpos[qpos_address(model, leader)]
            drift = data.qpos[qpos_address(model, joint)] - law
            worst_drift = max(worst_drift, abs(drift))
    assert worst_speed < 0.5, 'a finger joint reached %.3f rad/s' % worst_speed
    assert worst_drift < 0.01, 'a mimic joint drifted %.4f rad from its law' % worst_drift

