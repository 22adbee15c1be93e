"""Pure models behind the simulated FT 300 and 2F-140 (no ROS master)."""
import os

import numpy as np
import pytest
import yaml

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices import gripper_joint_states, gripper_model, wrench_model
from ur3_ft_gripper_description.devices.wrench_model import STANDARD_GRAVITY as G
from ur3_ft_gripper_testing.model import PACKAGE_DIR

PAYLOAD_YAML = os.path.join(PACKAGE_DIR, 'config', 'sim_devices.yaml')


# -- payload file --------------------------------------------------------------

def test_devices_file_holds_the_sensor_figures_and_no_second_mass_of_the_gripper():
    sensor = wrench_model.load_sensor_spec(PAYLOAD_YAML)
    with open(PAYLOAD_YAML) as f:
        assert 'payload' not in yaml.safe_load(f)  # the gripper's mass lives in the model
    assert sensor.frame_id == 'robotiq_ft_frame_id'
    assert sensor.noise_force > 0 and sensor.noise_torque > 0
    assert sensor.rate == pytest.approx(100.0)


def test_gripper_spec_file():
    spec = gripper_model.load_gripper_spec(PAYLOAD_YAML, ('stroke', 'min_speed', 'max_speed'))
    assert spec['stroke'] == pytest.approx(0.140)
    assert 0 < spec['min_speed'] < spec['max_speed']
    assert 0 <= spec['gpo_open'] < spec['gpo_closed'] <= 255
    with pytest.raises(ValueError, match='no nonsense'):
        gripper_model.load_gripper_spec(PAYLOAD_YAML, ('stroke', 'nonsense'))


def test_held_object_moves_the_centre_of_mass():
    gripper = wrench_model.Load(mass=1.0, com=[0, 0, 0.06])
    heavier = gripper.with_object(0.5, [0.0, 0.03, 0.24])
    assert heavier.mass == pytest.approx(1.5)
    assert np.allclose(heavier.com, [0.0, 0.01, 0.12])
    assert gripper.mass == 1.0  # the original is untouched
    assert gripper.with_object(0.0, [9, 9, 9]).com == pytest.approx(gripper.com)


def test_a_load_refuses_a_negative_mass():
    with pytest.raises(ValueError, match='finite number >= 0'):
        wrench_model.Load(mass=-1.0, com=[0, 0, 0])


# -- gravity wrench --------------------------------------------------------------

MASS, COM = 0.975, (0.0, 0.0, 0.062)


def wrench(rotation, mass=MASS, com=COM):
    """The wrench for a sensor with orientation `rotation` (3x3) in a z-up world."""
    g = rotation.T.dot([0.0, 0.0, -1.0])
    values = wrench_model.gravity_wrench(g[0], g[1], g[2], mass, com)
    return np.array(values[:3]), np.array(values[3:])


def test_sensor_pointing_down_is_pulled_along_plus_z():
    # Sensor z along world -z (tool pointing at the floor): rotation of pi about x.
    force, torque = wrench(kinematics.rpy_matrix(np.pi, 0, 0))
    assert np.allclose(force, [0, 0, MASS * G])
    assert np.allclose(torque, 0.0)  # COM on the line of action


def test_sensor_pointing_up_is_pushed_along_minus_z():
    force, torque = wrench(np.eye(3))
    assert np.allclose(force, [0, 0, -MASS * G])
    assert np.allclose(torque, 0.0)


def test_horizontal_sensor_sees_weight_across_and_a_lever_torque():
    # Sensor z along world +x, sensor x along world +z: world down is sensor -x.
    horizontal = np.column_stack([[0, 0, 1], [0, -1, 0], [1, 0, 0]]).astype(float)
    assert np.linalg.det(horizontal) == pytest.approx(1.0)
    force, torque = wrench(horizontal)
    assert np.allclose(force, [-MASS * G, 0, 0])
    # 0.062 m lever along z, weight along -x: torque = z x (-x) = -y.
    assert np.allclose(torque, [0, -0.062 * MASS * G, 0])


@pytest.mark.parametrize('rpy', [(0.3, -1.1, 2.0), (2.5, 0.4, -0.7), (-1.2, 1.3, 0.1)])
def test_any_orientation_magnitude_and_lever(rpy):
    com = (0.01, -0.02, 0.07)
    rotation = kinematics.rpy_matrix(*rpy)
    force, torque = wrench(rotation, com=com)
    assert np.linalg.norm(force) == pytest.approx(MASS * G)
    assert np.allclose(torque, np.cross(com, force))
    assert torque.dot(force) == pytest.approx(0.0, abs=1e-9)
    # Back in the world frame, the force points straight down.
    assert np.allclose(rotation.dot(force), [0, 0, -MASS * G])


def test_gravity_direction_of_any_length():
    force = wrench_model.gravity_wrench(0, 3.0, 0, 2.0, (0, 0, 0.1), g=10.0)[:3]
    assert np.allclose(force, [0, 20.0, 0])


def test_gravity_wrench_rejects_a_zero_direction():
    with pytest.raises(ValueError):
        wrench_model.gravity_wrench(0, 0, 0, MASS, COM)
    with pytest.raises(ValueError):
        wrench_model.gravity_wrench(float('nan'), 0, 1, MASS, COM)


# -- gripper opening <-> finger angle --------------------------------------------

@pytest.fixture(scope='module')
def gripper(default_model):
    return gripper_model.GripperKinematics(default_model.text)


def test_gripper_joint_range_comes_from_the_model(gripper, default_model):
    assert (gripper.lower, gripper.upper) == default_model.limits('finger_joint')
    assert gripper.lower == pytest.approx(0.0) and gripper.upper == pytest.approx(0.7)


def test_open_end_is_the_widest(gripper):
    assert gripper.opening(0.0) == pytest.approx(gripper.max_opening)
    assert gripper.max_opening == max(gripper.openings)
    # A 140 mm-class gripper: open between 0.10 and 0.15 m, closed about 0.
    assert 0.10 < gripper.max_opening < 0.15
    assert abs(gripper.min_opening) < 0.005


def test_opening_shrinks_monotonically(gripper):
    angles = np.linspace(0.0, 0.7, 301)
    openings = [gripper.opening(a) for a in angles]
    assert np.all(np.diff(openings) < 0)


def test_opening_matches_independent_forward_kinematics(gripper, default_model):
    # Pads' centre distance from the plain Model, less one pad thickness (box z = 0.0075).
    for a in (0.0, 0.2, 0.45, 0.7):
        positions = {'finger_joint': a}
        left = default_model.to_root('left_inner_finger_pad', positions)[:3, 3]
        right = default_model.to_root('right_inner_finger_pad', positions)[:3, 3]
        assert gripper.opening(a) == pytest.approx(np.linalg.norm(right - left) - 0.0075, abs=1e-6)


def test_round_trip(gripper):
    for a in np.linspace(0.0, 0.7, 37):
        assert gripper.angle(gripper.opening(a)) == pytest.approx(a, abs=1e-6)
    for o in np.linspace(gripper.min_opening, gripper.max_opening, 23):
        assert gripper.opening(gripper.angle(o)) == pytest.approx(o, abs=1e-7)


def test_endpoints_and_clamping_map_to_joint_limits(gripper):
    assert gripper.angle(gripper.max_opening) == pytest.approx(0.0, abs=1e-9)
    assert gripper.angle(gripper.min_opening) == pytest.approx(0.7, abs=1e-9)
    assert gripper.angle(1.0) == 0.0 and gripper.angle(-1.0) == 0.7
    assert gripper.opening(-0.5) == gripper.opening(0.0)
    assert gripper.opening(2.0) == gripper.opening(0.7)


# -- position register <-> opening --------------------------------------------------

def test_register_scale_spans_the_stroke_between_the_units_ends():
    scale = gripper_model.RegisterScale(0.140, 3, 230)
    assert scale.opening(3) == pytest.approx(0.140)
    assert scale.opening(230) == pytest.approx(0.0)
    assert scale.opening(116.5) == pytest.approx(0.070)
    assert scale.opening(0) == 0.140 and scale.opening(255) == 0.0  # beyond the ends: clamped
    for width in (0.0, 0.01, 0.07, 0.1285, 0.14):
        assert scale.opening(scale.position(width)) == pytest.approx(width, abs=1e-12)
    assert 1.0 / scale.counts_per_metre == pytest.approx(0.140 / 227)


@pytest.mark.parametrize('args', [(0.0, 3, 230), (0.14, 230, 3), (0.14, -1, 230), (0.14, 3, 256)])
def test_register_scale_rejects_impossible_calibrations(args):
    with pytest.raises(ValueError):
        gripper_model.RegisterScale(*args)


def test_every_register_value_maps_to_the_pad_gap_it_stands_for(default_model):
    fingers = gripper_model.GripperKinematics(default_model.text)
    scale = gripper_model.RegisterScale(0.140, 3, 230)
    table = gripper_joint_states.JointTable(fingers, scale)
    assert table.joint_name == 'finger_joint'
    assert table.angle(0) == table.angle(3) == pytest.approx(0.0)     # open (wider than the model)
    # Closed: the pads touch (the model's limit, 0.7 rad, overlaps them by 0.2 mm).
    assert fingers.opening(table.angle(230)) == pytest.approx(0.0, abs=1e-6)
    assert table.angle(230) == pytest.approx(0.7, abs=0.002) and table.angle(255) == table.angle(230)
    for gpo in range(3, 231):
        width = scale.opening(gpo)
        expected = min(width, fingers.max_opening)
        if width > fingers.min_opening:
            assert fingers.opening(table.angle(gpo)) == pytest.approx(expected, abs=1e-6), gpo
    angles = [table.angle(gpo) for gpo in range(256)]
    assert all(b >= a for a, b in zip(angles, angles[1:]))  # closing never opens


def test_prefixed_model(expand_model):
    model = expand_model(prefix='left_')
    gripper = gripper_model.GripperKinematics(model.text, prefix='left_')
    assert gripper.angle(gripper.opening(0.3)) == pytest.approx(0.3, abs=1e-6)
    with pytest.raises(ValueError):
        gripper_model.GripperKinematics(model.text)  # no unprefixed finger_joint


def test_step_toward():
    assert gripper_model.step_toward(0.14, 0.0, 0.1, 0.01) == pytest.approx(0.139)
    assert gripper_model.step_toward(0.0, 0.14, 0.1, 0.01) == pytest.approx(0.001)
    assert gripper_model.step_toward(0.05, 0.0505, 0.1, 0.01) == 0.0505  # no overshoot
    assert gripper_model.step_toward(0.05, 0.05, 0.1, 0.01) == 0.05
    position = 0.14
    for _ in range(100):  # 1 s at 100 Hz and 0.15 m/s covers the stroke
        position = gripper_model.step_toward(position, 0.0, 0.15, 0.01)
    assert position == 0.0
    with pytest.raises(ValueError):
        gripper_model.step_toward(0.0, 0.1, -1.0, 0.01)
