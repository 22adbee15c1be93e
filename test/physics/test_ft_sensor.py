"""The FT 300 on physics: its reading against a known load's weight and MuJoCo's contact force.

Known truths: the kinematic simulation's reading for the model's tool-side load
(wrench_model.gravity_wrench with inertials.mass_below, in the sensor frame from the URDF's
forward kinematics), a held mass's weight m*g, and the force of MuJoCo's contact solver.
"""
import math

import numpy as np
import pytest

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices import wrench_model
from ur3_ft_gripper_description.model import inertials
from ur3_ft_gripper_testing.physics import ARM_JOINTS, START, STANDARD_GRAVITY, TABLE, Arm, close_on

FRAME = 'robotiq_ft_frame_id'
POSES = {
    'tool_down': START,
    'tool_sideways': START + np.array([0.0, 0.0, 0.0, 0.0, math.pi / 2, 0.0]),
    'tool_up': START + np.array([0.0, 0.0, 0.0, math.pi, 0.0, 0.0]),
    'tilted': START + np.array([0.4, 0.2, -0.3, 0.7, 0.9, 1.1]),
}


def expected_at_rest(urdf_text, arm):
    """What the kinematic simulation reads for the model's tool side at joint positions `arm`."""
    model = kinematics.Model(urdf_text)
    mass, com = inertials.mass_below(model, FRAME)
    rotation = model.transform(model.root(), FRAME, dict(zip(ARM_JOINTS, arm)))[:3, :3]
    gx, gy, gz = rotation.T.dot([0.0, 0.0, -1.0])
    return np.array(wrench_model.gravity_wrench(gx, gy, gz, mass, com)), mass


@pytest.mark.parametrize('pose', sorted(POSES))
def test_at_rest_the_reading_is_the_kinematic_simulations(make_cell, robot, pose):
    cell = make_cell('', POSES[pose])
    Arm(cell).hold(1.0)
    expected, mass = expected_at_rest(robot[1], POSES[pose])
    reading = cell.wrench()
    weight = mass * STANDARD_GRAVITY
    assert np.linalg.norm(reading[:3] - expected[:3]) < 0.005 * weight, (reading, expected)
    assert np.linalg.norm(reading[3:] - expected[3:]) < 0.005 * weight * 0.1, (reading, expected)


@pytest.mark.parametrize('pose', sorted(POSES))
def test_at_rest_the_accelerometer_reads_one_g_against_gravity_in_the_sensor_frame(make_cell, robot, pose):
    # Held still, an accelerometer reads gravity's reaction: 1 g, world up, here in the sensor frame from
    # the URDF's forward kinematics.
    cell = make_cell('', POSES[pose])
    Arm(cell).hold(1.0)
    model = kinematics.Model(robot[1])
    rotation = model.transform(model.root(), FRAME, dict(zip(ARM_JOINTS, POSES[pose])))[:3, :3]
    expected = rotation.T.dot([0.0, 0.0, STANDARD_GRAVITY])
    assert np.linalg.norm(cell.accelerometer() - expected) < 0.01 * STANDARD_GRAVITY, (cell.accelerometer(), expected)


def test_a_hanging_load_pulls_along_z_when_the_sensor_z_points_down(make_cell, robot):
    cell = make_cell('', START)
    Arm(cell).hold(1.0)
    _, mass = expected_at_rest(robot[1], START)
    fx, fy, fz = cell.wrench()[:3]
    assert fz == pytest.approx(mass * STANDARD_GRAVITY, rel=0.005)
    assert abs(fx) < 0.01 and abs(fy) < 0.01
    cell = make_cell('', POSES['tool_up'])
    Arm(cell).hold(1.0)
    assert cell.wrench()[2] == pytest.approx(-mass * STANDARD_GRAVITY, rel=0.005)


def test_the_tool_side_weighs_what_robotiqs_manual_says(make_cell):
    # 2F-140 on the FT 300's tool side: the manual's FT 300 + 2F-140 less the FT 300 alone.
    import yaml
    import rospkg
    import os
    with open(os.path.join(rospkg.RosPack().get_path('ur3_ft_gripper_description'), 'config',
                           'robotiq_mass.yaml')) as f:
        figures = yaml.safe_load(f)
    gripper = figures['ft300_with_2f140']['mass'] - figures['ft300']['mass']
    cell = make_cell('', START)
    Arm(cell).hold(1.0)
    assert np.linalg.norm(cell.wrench()[:3]) == pytest.approx(gripper * STANDARD_GRAVITY, rel=0.02)


def contact_force_on_robot(cell):
    """Sum (world frame) of the forces MuJoCo's contact solver applies to the robot's bodies."""
    mujoco = cell.mujoco
    model, data = cell.model, cell.data
    robot = set(cell.robot_bodies)
    total = np.zeros(3)
    for i in range(data.ncon):
        contact = data.contact[i]
        bodies = [model.geom_bodyid[contact.geom1], model.geom_bodyid[contact.geom2]]
        if (bodies[0] in robot) == (bodies[1] in robot):
            continue
        local = np.zeros(6)
        mujoco.mj_contactForce(model, data, i, local)
        # The contact force acts on geom2 along the frame's normal (from geom1 to geom2).
        force = contact.frame.reshape(3, 3).T.dot(local[:3])
        total += force if bodies[1] in robot else -force
    return total


def test_pressed_on_the_table_the_z_force_is_the_contacts(make_cell):
    """Fingers closed, the tool lowered onto the table, then pressed down 0.1 mm at a time to 20 N, held still."""
    cell = make_cell(TABLE, START)
    arm = Arm(cell)
    close_on(cell, 60.0, speed=0.25)
    arm.hold(0.5)
    zero = cell.wrench()

    def pressed():
        return cell.wrench()[2] - zero[2]
    assert arm.move_tool([0.0, 0.0, -0.1], 10.0, until=lambda: abs(pressed()) > 2.0), 'the tool never reached the table'
    arm.hold(0.5)
    while abs(pressed()) < 20.0:
        arm.move_tool([0.0, 0.0, -0.0001], 0.05)
        arm.hold(0.3)
        assert cell.protective_stop is None
    arm.hold(1.0)
    sensor = cell.body_pose('robotiq_ft_frame_id')[1]
    contact = sensor.T.dot(contact_force_on_robot(cell))
    measured = cell.wrench() - zero
    assert abs(contact[2]) > 19.0, contact
    assert measured[2] == pytest.approx(contact[2], rel=0.005), (measured, contact)


@pytest.mark.parametrize('mass', [0.3, 1.0])
def test_hanging_still_after_zeroing_a_held_mass_weighs_m_g(make_cell, between_pads, mass):
    cell = make_cell(between_pads(0.05, mass=mass), START)
    arm = Arm(cell)
    arm.hold(0.5)
    zero = cell.wrench()  # SET_ZERO with the gripper empty, in the pose it will weigh in
    assert close_on(cell, 60.0).motion == 'on_object'
    arm.move_tool([0.0, 0.0, 0.15], 1.5)
    arm.hold(1.0)
    assert cell.object_pose('held')[0][2] > 0.2, 'the object was not lifted'
    weight = np.linalg.norm((cell.wrench() - zero)[:3])
    assert weight == pytest.approx(mass * STANDARD_GRAVITY, rel=0.02)
