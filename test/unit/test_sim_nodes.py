"""The simulated-device nodes' logic without a ROS master: parameters, warnings, motion."""
import math

import numpy as np
import pytest

from ur3_ft_gripper_description import ft300_sim, gripper_model, gripper_sim, kinematics, sim_params, wrench_model
from ur3_ft_gripper_description.wrench_model import STANDARD_GRAVITY as G


def params(**values):
    """A get_param(name, default) over `values`, keyed without the '~'."""
    return lambda name, default: values.get(name.lstrip('~'), default)


class Log(object):
    def __init__(self):
        self.lines = []

    def __call__(self, text):
        self.lines.append(text)


# -- ft300_sim parameters --------------------------------------------------------

def test_ft300_defaults_are_the_real_devices():
    settings = ft300_sim.FT300Settings.from_params(params())
    assert settings.frame_id == 'robotiq_ft_frame_id'
    assert settings.gravity_frame == 'base_link'
    assert settings.rate == pytest.approx(100.0)
    assert settings.noise_force == pytest.approx(0.1)
    assert settings.noise_torque == pytest.approx(0.005)
    assert settings.payload.mass == pytest.approx(0.975)


def test_ft300_default_frames_follow_the_prefix():
    settings = ft300_sim.FT300Settings.from_params(params(prefix='left_'))
    assert (settings.frame_id, settings.gravity_frame) == ('left_robotiq_ft_frame_id', 'left_base_link')


def test_ft300_held_object_is_added_to_the_gripper():
    settings = ft300_sim.FT300Settings.from_params(params(payload_mass=0.5, payload_com='0 0 0.2'))
    assert settings.payload.mass == pytest.approx(1.475)
    expected_z = (0.975 * 0.062 + 0.5 * 0.2) / 1.475
    assert settings.payload.com == pytest.approx([0.0, 0.0, expected_z])


def test_ft300_without_gripper_carries_only_the_held_object():
    settings = ft300_sim.FT300Settings.from_params(params(gripper_mounted=False))
    assert settings.payload.mass == 0.0
    settings = ft300_sim.FT300Settings.from_params(
        params(gripper_mounted=False, payload_mass=0.3, payload_com=[0, 0, 0.1]))
    assert settings.payload.mass == pytest.approx(0.3)
    assert settings.payload.com == pytest.approx([0, 0, 0.1])


@pytest.mark.parametrize('values, named', [
    (dict(gripper_mounted='no'), '~gripper_mounted'),
    (dict(rate=0), '~rate'),
    (dict(rate='fast'), '~rate'),
    (dict(noise_force=-0.1), '~noise_force'),
    (dict(noise_torque=float('nan')), '~noise_torque'),
    (dict(payload_mass=-1), '~payload_mass'),
    (dict(payload_com=[0, 0]), '~payload_com'),
    (dict(payload_com='a b c'), '~payload_com'),
    (dict(frame_id='/robotiq_ft_frame_id'), '~frame_id'),
    (dict(gravity_frame=''), '~gravity_frame'),
    (dict(devices_file='/nonexistent/sim_devices.yaml'), '~devices_file'),
    (dict(max_pose_age=0), '~max_pose_age'),
])
def test_ft300_bad_parameter_is_one_line_naming_it(values, named):
    with pytest.raises(sim_params.ParamError) as error:
        ft300_sim.FT300Settings.from_params(params(**values))
    text = str(error.value)
    assert text.startswith(named) and '\n' not in text


def test_ft300_devices_file_without_payload_is_rejected(tmp_path):
    bad = tmp_path / 'devices.yaml'
    bad.write_text('sensor: {rate: 100}\n')
    with pytest.raises(sim_params.ParamError, match="no 'payload' section"):
        ft300_sim.FT300Settings.from_params(params(devices_file=str(bad)))


# -- sensor model ------------------------------------------------------------------

def noise_free(**values):
    return ft300_sim.FT300Settings.from_params(params(noise_force=0, noise_torque=0, **values))


TOOL_DOWN = kinematics.rpy_matrix(math.pi, 0, 0)


def test_reading_is_the_gripper_weight():
    sensor = ft300_sim.SensorModel(noise_free())
    force, torque = sensor.read(TOOL_DOWN)
    assert force == pytest.approx([0, 0, 0.975 * G])
    assert torque == pytest.approx([0, 0, 0], abs=1e-12)


def test_zero_needs_a_pose_then_takes_the_noise_free_reading():
    sensor = ft300_sim.SensorModel(ft300_sim.FT300Settings.from_params(params()),
                                   rng=np.random.default_rng(1))
    assert not sensor.set_zero()
    sensor.read(TOOL_DOWN)
    assert sensor.set_zero()
    samples = np.array([np.concatenate(sensor.read(TOOL_DOWN)) for _ in range(2000)])
    # Zero-mean noise of the datasheet spread around zero, not around the weight.
    assert np.allclose(samples[:, :3].mean(axis=0), 0, atol=0.01)
    assert np.allclose(samples[:, :3].std(axis=0), 0.1, rtol=0.1)
    assert np.allclose(samples[:, 3:].std(axis=0), 0.005, rtol=0.1)


def test_after_zero_a_new_pose_reads_the_difference():
    sensor = ft300_sim.SensorModel(noise_free())
    sensor.read(TOOL_DOWN)
    sensor.set_zero()
    force, _ = sensor.read(np.eye(3))  # tool pointing up: weight along -z
    assert force == pytest.approx([0, 0, -2 * 0.975 * G])


def test_fast_reading_equals_the_reference_model_for_any_orientation():
    # The node's float arithmetic against wrench_model's numpy reference, for
    # rotation matrices and the quaternions that tf2 hands the node.
    settings = ft300_sim.FT300Settings.from_params(
        params(noise_force=0, noise_torque=0, payload_mass=0.4, payload_com=[0.01, -0.02, 0.15]))
    sensor = ft300_sim.SensorModel(settings)
    rng = np.random.default_rng(3)
    for q in rng.normal(size=(50, 4)):
        x, y, z, w = q / np.linalg.norm(q)
        rotation = kinematics.quaternion_matrix(x, y, z, w)
        force, torque = wrench_model.gravity_wrench(rotation, settings.payload.mass, settings.payload.com)
        for got in (sensor.read(rotation), sensor.read_quaternion(x, y, z, w)):
            assert got[0] == pytest.approx(force, abs=1e-12)
            assert got[1] == pytest.approx(torque, abs=1e-12)


# -- pose watch ----------------------------------------------------------------------

def watch(start=100.0):
    warn, info = Log(), Log()
    return ft300_sim.PoseWatch(noise_free(), warn, info, start_time=start), warn, info


def test_waiting_for_tf_warns_once_after_a_quiet_start():
    w, warn, _ = watch()
    w.missing('no frame', now=100.5)
    assert warn.lines == []  # a normal bring-up is quiet
    for t in (101.0, 101.5, 102.0, 110.0):
        w.missing('no frame', now=t)
    assert len(warn.lines) == 1 and 'waiting for TF base_link -> robotiq_ft_frame_id' in warn.lines[0]


def test_stale_pose_warns_once_and_resume_is_reported():
    w, warn, info = watch()
    assert w.fresh(transform_stamp=100.0, now=100.1)
    assert not w.fresh(transform_stamp=100.0, now=101.0)
    assert not w.fresh(transform_stamp=100.0, now=105.0)
    assert len(warn.lines) == 1 and '1.00 s old' in warn.lines[0]
    assert w.fresh(transform_stamp=105.0, now=105.1)
    assert len(info.lines) == 2  # first pose, then resumed


def test_static_transform_is_never_stale():
    w, warn, _ = watch()
    assert w.fresh(transform_stamp=0.0, now=1e6)
    assert warn.lines == []


def test_lost_tf_after_publishing_warns_once():
    w, warn, _ = watch()
    w.fresh(100.0, 100.0)
    w.missing('gone', now=100.2)
    w.missing('gone', now=100.3)
    assert len(warn.lines) == 1 and 'lost TF' in warn.lines[0]


# -- gripper_sim ------------------------------------------------------------------------

def test_gripper_defaults_are_the_real_devices():
    settings = gripper_sim.settings_from_params(params())
    assert settings['stroke'] == pytest.approx(0.140)
    assert settings['speed'] == pytest.approx(0.250)
    assert settings['rate'] == pytest.approx(50.0)
    assert settings['initial_opening'] == pytest.approx(0.140)
    assert settings['notes'] == []


def test_gripper_speed_outside_the_device_range_is_allowed_with_a_note():
    settings = gripper_sim.settings_from_params(params(speed=1.0))
    assert settings['speed'] == 1.0 and '0.03..0.25' in settings['notes'][0]


@pytest.mark.parametrize('values, named', [
    (dict(speed=0), '~speed'), (dict(rate=-1), '~rate'),
    (dict(initial_opening=0.2), '~initial_opening'), (dict(initial_opening=-0.1), '~initial_opening'),
])
def test_gripper_bad_parameter_is_one_line_naming_it(values, named):
    with pytest.raises(sim_params.ParamError) as error:
        gripper_sim.settings_from_params(params(**values))
    assert str(error.value).startswith(named)


@pytest.mark.parametrize('value, kind', [
    (float('nan'), 'nan'), (float('inf'), 'inf'), (-float('inf'), 'inf'),
    (-0.001, 'below'), (0.1401, 'above'), (1e9, 'above')])
def test_bad_commands_are_named(value, kind):
    assert gripper_sim.command_problem(value, 0.140)[0] == kind


@pytest.mark.parametrize('value', [0.0, 0.07, 0.140])
def test_commands_in_the_stroke_are_valid(value):
    assert gripper_sim.command_problem(value, 0.140) is None


def test_bad_commands_are_ignored_and_warned_once_per_kind():
    warn, clock = Log(), [100.0]
    state = gripper_sim.GripperState(0.140, 0.25, 0.140, warn, clock=lambda: clock[0])
    assert state.command(0.05)
    for value in [float('nan'), 0.5, float('nan'), 0.6, -1.0, float('inf')] * 100:
        assert not state.command(value)
    assert state.target == 0.05
    assert len(warn.lines) == 4  # nan, above, below, inf
    assert all('between 0.0 (closed) and 0.14 (open)' in line for line in warn.lines)
    clock[0] += gripper_sim.REWARN_AFTER
    assert state.command(0.06)  # a valid command re-arms the warnings
    state.command(0.5)
    assert len(warn.lines) == 5 and state.target == 0.06


def test_bad_commands_alternating_with_good_ones_warn_once_per_kind_and_second():
    warn, clock = Log(), [100.0]
    state = gripper_sim.GripperState(0.140, 0.25, 0.140, warn, clock=lambda: clock[0])
    for i in range(3000):  # 3 s of 1000 commands per second, every other one bad
        clock[0] += 0.001
        assert state.command(float('nan') if i % 2 else 0.001 * (i % 140)) != bool(i % 2)
    assert len(warn.lines) == 3  # at 100.001, 101.001 (+/- a step), 102.00x
    assert state.target == pytest.approx(0.001 * (2998 % 140))


def test_gripper_moves_at_its_speed_and_stops_on_target():
    state = gripper_sim.GripperState(0.140, 0.25, 0.140, Log())
    state.command(0.0)
    positions = [state.advance(0.02) for _ in range(40)]
    assert positions[0] == pytest.approx(0.140 - 0.005)
    assert np.allclose(np.diff(positions[:20]), -0.005)
    assert positions[-1] == 0.0 and min(positions) == 0.0  # 0.56 s for the stroke, no overshoot


def test_table_angle_matches_the_exact_inverse(default_model):
    fingers = gripper_model.GripperKinematics(default_model.text, samples=gripper_sim.ANGLE_TABLE_SAMPLES)
    for command in np.linspace(0.0, 0.140, 57):
        opening = fingers.command_to_opening(command)
        assert fingers.table_angle(opening) == pytest.approx(fingers.angle(opening), abs=1e-6)


# -- master watch ------------------------------------------------------------------

class FakeMaster(object):
    """rosgraph.Master's lookupNode as a restarted or unreachable master answers it."""
    master_uri = 'http://localhost:11311'

    def __init__(self):
        self.answer = 'http://node:1/'

    def lookupNode(self, name):
        import rosgraph
        if isinstance(self.answer, Exception):
            raise self.answer
        if self.answer is None:
            raise rosgraph.MasterError('unknown node [%s]' % name)
        return self.answer


def master_watch_with(register_all):
    from ur3_ft_gripper_description import master_watch
    master, warn, info, fatal, shutdowns = FakeMaster(), Log(), Log(), Log(), []
    watch = master_watch.MasterWatch('/gripper_sim', master, register_all, warn, info, fatal,
                                     shutdowns.append)
    return watch, master, warn, info, fatal, shutdowns


def test_master_outage_warns_once_and_a_restart_reregisters_once():
    calls = []
    watch, master, warn, info, fatal, _ = master_watch_with(lambda: calls.append(1) or 7)
    assert watch.check('http://node:1/') == 'ok' and not calls
    master.answer = ConnectionRefusedError(111, 'Connection refused')
    for _ in range(5):
        assert watch.check('http://node:1/') == 'unreachable'
    assert len(warn.lines) == 1 and 'unreachable' in warn.lines[0]
    master.answer = None  # a new master: it does not know the node
    assert watch.check('http://node:1/') == 'ok'
    master.answer = 'http://node:1/'
    assert watch.check('http://node:1/') == 'ok'
    assert calls == [1] and len(info.lines) == 1 and 'registered' in info.lines[0]
    assert fatal.lines == [] and watch.exit_status == 0


def test_failed_reregistration_exits_with_one_line():
    def fail():
        raise OSError('connection reset')
    watch, master, _, _, fatal, shutdowns = master_watch_with(fail)
    master.answer = None
    assert watch.check('http://node:1/') == 'failed'
    assert watch.check('http://node:1/') == 'failed'
    assert len(fatal.lines) == 1 and 'start the node again' in fatal.lines[0]
    assert len(shutdowns) == 1 and watch.exit_status == 1
