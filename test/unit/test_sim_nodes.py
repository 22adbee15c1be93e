"""The simulated-device nodes' logic without a ROS master: parameters, warnings, motion."""

import os

import numpy as np
import pytest
import yaml
from transforms3d.quaternions import quat2mat

from ur3_ft_gripper_description.devices import ft300_sim, gripper_joint_states, gripper_sim, sim_params, wrench_model
from ur3_ft_gripper_testing.model import PACKAGE_DIR, configured


def params(**values):
    """A get_param(name, default) over `values`, keyed without the '~'; robot_description: the default model."""
    values.setdefault('robot_description', configured('ur3', True, True).text)
    return lambda name, default: values.get(name.lstrip('~'), default)


def manual_gripper_com_z():
    """The 2F-140's centre of mass along the sensor axis, from the manual's figures and the model's sensor frame."""
    with open(os.path.join(PACKAGE_DIR, 'config', 'robotiq_mass.yaml')) as f:
        figures = yaml.safe_load(f)
    alone, both = figures['ft300'], figures['ft300_with_2f140']
    from_tool0 = ((both['mass'] * both['com_z_from_tool0'] - alone['mass'] * alone['com_z_from_tool0'])
                  / (both['mass'] - alone['mass']))
    return from_tool0 - configured('ur3', True, True).transform('tool0', 'robotiq_ft_frame_id')[2, 3]


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
    # The load is the model's gripper, with the FT 300 manual's figures (and gripper_tcp's 10 mg).
    assert settings.load.mass == pytest.approx(0.975, abs=2e-5)
    assert settings.load.com == pytest.approx([0.0, 0.0, manual_gripper_com_z()], abs=2e-4)


def test_ft300_default_frames_follow_the_prefix():
    settings = ft300_sim.FT300Settings.from_params(
        params(prefix='left_', robot_description=configured('ur3', True, True, prefix='left_').text))
    assert (settings.frame_id, settings.gravity_frame) == ('left_robotiq_ft_frame_id', 'left_base_link')


def test_ft300_held_object_is_added_to_the_gripper():
    gripper = ft300_sim.FT300Settings.from_params(params()).load
    settings = ft300_sim.FT300Settings.from_params(params(payload_mass=0.5, payload_com='0 0 0.2'))
    assert settings.load.mass == pytest.approx(gripper.mass + 0.5)
    expected = (gripper.mass * gripper.com + 0.5 * np.array([0, 0, 0.2])) / (gripper.mass + 0.5)
    assert settings.load.com == pytest.approx(expected)


def test_ft300_without_gripper_carries_only_the_held_object():
    sensor_only = configured('ur3', True, False).text
    settings = ft300_sim.FT300Settings.from_params(params(robot_description=sensor_only))
    assert settings.load.mass == 0.0
    settings = ft300_sim.FT300Settings.from_params(
        params(robot_description=sensor_only, payload_mass=0.3, payload_com=[0, 0, 0.1]))
    assert settings.load.mass == pytest.approx(0.3)
    assert settings.load.com == pytest.approx([0, 0, 0.1])


@pytest.mark.parametrize('values, named', [
    (dict(robot_description=''), 'robot_description'),
    (dict(robot_description='<robot name="r"><link name="a"/></robot>'), 'robot_description'),
    (dict(robot_description='<robot'), 'robot_description'),
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
    (dict(unit_offset=[1, 2, 3, 4, 5]), '~unit_offset'),
    (dict(unit_offset='0 0 0 0 0 inf'), '~unit_offset'),
])
def test_ft300_bad_parameter_is_one_line_naming_it(values, named):
    with pytest.raises(sim_params.ParamError) as error:
        ft300_sim.FT300Settings.from_params(params(**values))
    text = str(error.value)
    assert text.startswith(named) and '\n' not in text


def test_ft300_devices_file_without_sensor_is_rejected(tmp_path):
    bad = tmp_path / 'devices.yaml'
    bad.write_text('gripper: {stroke: 0.14}\n')
    with pytest.raises(sim_params.ParamError, match="no 'sensor' section"):
        ft300_sim.FT300Settings.from_params(params(devices_file=str(bad)))


# -- sensor model ------------------------------------------------------------------

def noise_free(**values):
    return ft300_sim.FT300Settings.from_params(params(noise_force=0, noise_torque=0, **values))


DOWN, UP = (0.0, 0.0, 1.0), (0.0, 0.0, -1.0)  # gravity in the sensor frame: tool down, tool up


def on_grid(values):
    """The values are whole counts of 0.01 N / 0.001 Nm, as float32 carries them."""
    for v, r in zip(values, (0.01,) * 3 + (0.001,) * 3):
        assert abs(v / r - round(v / r)) < 1e-3, values
        assert v == float(np.float32(v))


# The unit's offset of config/sim_devices.yaml, a user's FT 300 at rest.
USERS_UNIT = wrench_model.load_sensor_spec(sim_params.default_devices_file()).unit_offset


def test_a_sensor_never_zeroed_reads_its_units_offset_beside_the_weight():
    assert np.linalg.norm(USERS_UNIT[:3]) > 20.0  # tens of newtons, as real units read before zeroing
    sensor = ft300_sim.SensorModel(noise_free())
    reading = np.array(sensor.read_gravity(*DOWN))
    assert reading[:3] == pytest.approx(np.add(USERS_UNIT[:3], (0, 0, 9.56)), abs=1e-5)
    assert reading[3:] == pytest.approx(USERS_UNIT[3:], abs=0.0021)
    on_grid(reading)
    # The device's own reading, which its registers and stream carry, is the same until SET_ZERO.
    assert sensor.device_reading() == tuple(reading)


def test_set_zero_is_the_drivers_the_device_goes_on_sending_its_offset():
    sensor = ft300_sim.SensorModel(noise_free())
    sensor.read_gravity(*DOWN)
    sensor.request_zero()
    assert sensor.read_gravity(*UP) == pytest.approx((0, 0, -2 * 9.5615, 0, 0, 0), abs=0.006)
    device = np.array(sensor.device_reading())
    assert device[:3] == pytest.approx(np.add(USERS_UNIT[:3], (0, 0, -9.5615)), abs=0.006)


def test_reading_is_the_gripper_weight_in_the_devices_resolution():
    sensor = ft300_sim.SensorModel(noise_free(unit_offset=[0] * 6))
    reading = sensor.read_gravity(*DOWN)
    assert reading[:3] == pytest.approx((0, 0, 9.56), abs=1e-6)  # 0.975 kg * g = 9.5615 N
    # The meshes put the centre of mass within 0.2 mm of the axis: at most a count or two of torque.
    assert reading[3:] == pytest.approx((0, 0, 0), abs=0.0021)
    on_grid(reading)


def test_quaternion_reading_equals_the_rotation_matrix_one():
    settings = noise_free(payload_mass=0.4, payload_com=[0.01, -0.02, 0.15])
    sensor = ft300_sim.SensorModel(settings)
    rng = np.random.default_rng(3)
    for q in rng.normal(size=(50, 4)):
        x, y, z, w = q / np.linalg.norm(q)
        g = quat2mat((w, x, y, z)).T.dot([0, 0, -1])
        got = sensor.read_quaternion(x, y, z, w)
        assert got == sensor.read_gravity(*g)
        on_grid(got)


def test_device_resolution_and_range():
    assert ft300_sim.as_device_sends((1.234, -0.005, 400.0, 0.0123, -0.0004, -50.0)) == pytest.approx(
        (1.23, 0.0, 327.67, 0.012, 0.0, -32.768), rel=1e-6, abs=1e-6)  # 16-bit counts saturate


def test_zero_takes_the_reading_before_it_then_readings_are_relative():
    sensor = ft300_sim.SensorModel(ft300_sim.FT300Settings.from_params(params()),
                                   rng=np.random.default_rng(1))
    sensor.read_gravity(*DOWN)
    sensor.request_zero()
    samples = np.array([sensor.read_gravity(*DOWN) for _ in range(2000)])
    # Zero-mean noise of the datasheet spread around zero, not around the weight.
    assert np.allclose(samples[:, :3].mean(axis=0), 0, atol=0.01)
    assert np.allclose(samples[:, :3].std(axis=0), 0.1, rtol=0.1)
    assert np.allclose(samples[:, 3:].std(axis=0), 0.005, rtol=0.1)


def test_after_zero_a_new_pose_reads_the_difference():
    sensor = ft300_sim.SensorModel(noise_free())
    sensor.read_gravity(*DOWN)
    sensor.request_zero()
    assert sensor.read_gravity(*DOWN) == pytest.approx((0,) * 6, abs=1e-6)
    assert sensor.read_gravity(*UP)[2] == pytest.approx(-2 * 9.5615, abs=0.006)


def test_zero_before_any_reading_zeroes_the_first():
    sensor = ft300_sim.SensorModel(noise_free())
    sensor.request_zero()
    assert sensor.read_gravity(*DOWN) == pytest.approx((0,) * 6, abs=1e-6)


def test_a_zero_requested_ahead_of_the_readings_sent_takes_the_one_at_the_request():
    # On physics this node reads the cell's samples in order and on a busy machine runs behind: a zero
    # asked at reading 5 leaves readings 3 and 4 as they were, and takes reading 4 as the zero.
    settings = noise_free()
    sensor = ft300_sim.SensorModel(settings)
    poses = {index: DOWN if index < 5 else UP for index in range(3, 8)}
    sensor.read_gravity(*DOWN)
    sensor.request_zero(index=5)
    read = {index: sensor.read(wrench_model.gravity_wrench(*poses[index], settings.load.mass, settings.load.com),
                               index) for index in sorted(poses)}
    unzeroed = 9.5615 + USERS_UNIT[2]  # the gripper's weight and the unit's offset
    assert read[3][2] == read[4][2] == pytest.approx(unzeroed, abs=0.006)
    assert read[5][2] == pytest.approx(-2 * 9.5615, abs=0.006)  # relative to reading 4, the tool down


# -- robotiq_ft_sensor_acc, as rq_sensor answers -------------------------------------

IDENTITY = dict(serial_number='SIM-0001', firmware_version='FTS-0.0.0', production_year='2026')


class AccLog(object):
    """The loggers accessor_reply takes, recording what they were given."""

    def __init__(self):
        self.infos, self.warnings = [], []

    def info(self, text):
        self.infos.append(text)

    def warn(self, text):
        self.warnings.append(text)

    def warn_once(self, text):
        if text not in self.warnings:
            self.warnings.append(text)


class ZeroCounter(object):
    def __init__(self):
        self.zeroes = 0

    def request_zero(self, index=None):
        self.zeroes += 1


def acc(command_id=0, command=''):
    """(reply, zero requests, info lines, warnings) of one robotiq_ft_sensor_acc request."""
    sensor, log = ZeroCounter(), AccLog()
    reply = ft300_sim.accessor_reply(command_id, command, sensor, IDENTITY, log)
    return reply, sensor.zeroes, log.infos, log.warnings


@pytest.mark.parametrize('command_id, res', [(1, 'SIM-0001'), (2, 'FTS-0.0.0'), (4, '2026')])
def test_acc_ids_answer_the_identity(command_id, res):
    assert acc(command_id)[:2] == ((True, res), 0)


def test_acc_set_zero():
    (reply, zeroes, _, warnings) = acc(8)
    assert reply == (True, 'Done') and zeroes == 1 and warnings == []


@pytest.mark.parametrize('command_id', [0, 3, 5, 7, 9, 16, 255])
def test_acc_unknown_id_fails_with_the_drivers_answer_and_warning(command_id):
    reply, zeroes, _, warnings = acc(command_id)
    assert reply == (False, 'Unsupported command_id') and zeroes == 0
    assert warnings == ["Unsupported command_id '%d', should be in [1, 2, 4, 8]" % command_id]


@pytest.mark.parametrize('command, res, zeroes', [
    ('GET SNU', 'SIM-0001', 0), ('GET FWV', 'FTS-0.0.0', 0), ('GET PYE', '2026', 0),
    ('SET ZRO', 'Done', 1),
    ('GET XYZ', '', 0), ('SET SNU', '', 0), ('PUT ZRO', '', 0), ('SET ZERO', '', 0), ('ZRO', '', 0)])
def test_acc_legacy_strings_answer_as_rq_sensor_and_never_report_success(command, res, zeroes):
    reply, got_zeroes, info, warnings = acc(8, command)  # the string wins over the id
    assert reply == (False, res) and got_zeroes == zeroes
    assert info == ['I heard: [%s]' % command, 'I send: [%s]' % res]
    assert warnings == ['Usage of command-string is deprecated, please use the numeric command_id']


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


# -- gripper_sim: the register interface -------------------------------------------------

SPEC = gripper_sim.spec_from_params(params())
ACTIVATION = SPEC.activation_time


def command(**registers):
    values = dict.fromkeys(gripper_sim.COMMAND_FIELDS, 0)
    values.update(registers)
    return values


class Clock(object):
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def gripper(**kwargs):
    warn, clock = Log(), Clock()
    return gripper_sim.RegisterGripper(SPEC, warn, clock=clock, **kwargs), warn, clock


def run_for(g, seconds, dt=0.02):
    for _ in range(int(round(seconds / dt))):
        g.advance(dt)
    return g.status()


def active(**kwargs):
    g, warn, clock = gripper(**kwargs)
    g.set_command(command(rACT=1))
    run_for(g, ACTIVATION + 0.1)
    return g, warn, clock


def test_gripper_defaults_come_from_the_devices_file():
    spec, rate, width, initial = gripper_sim.settings_from_params(params())
    assert (spec.stroke, spec.gpo_open, spec.gpo_closed) == (0.140, 3, 230)
    assert rate == 50.0 and width is None and initial == 3
    assert spec.speed_counts(255) == pytest.approx(0.250 * 227 / 0.140)
    assert spec.speed_counts(0) == pytest.approx(0.030 * 227 / 0.140)


@pytest.mark.parametrize('values, named', [
    (dict(rate=-1), '~rate'), (dict(object_width=-0.01), '~object_width'),
    (dict(object_width=0.2), '~object_width'), (dict(object_width='wide'), '~object_width'),
    (dict(initial_position=300), '~initial_position'),
    (dict(devices_file='/nonexistent.yaml'), '~devices_file')])
def test_gripper_bad_parameter_is_one_line_naming_it(values, named):
    with pytest.raises(sim_params.ParamError) as error:
        gripper_sim.settings_from_params(params(**values))
    assert str(error.value).startswith(named) and '\n' not in str(error.value)


def test_gripper_devices_file_without_a_register_figure_is_rejected(tmp_path):
    bad = tmp_path / 'devices.yaml'
    bad.write_text('gripper: {stroke: 0.14, min_speed: 0.03, max_speed: 0.25}\n')
    with pytest.raises(sim_params.ParamError, match='gpo_open'):
        gripper_sim.settings_from_params(params(devices_file=str(bad)))


def test_power_up_is_reset_and_motion_requests_need_the_activation_bit():
    g, _, _ = gripper()
    assert g.status() == dict(gACT=0, gGTO=0, gSTA=0, gOBJ=0, gFLT=0, gPR=0, gPO=3, gCU=0)
    g.set_command(command(rGTO=1, rPR=200, rSP=255))
    status = run_for(g, 0.5)
    assert status['gFLT'] == 0x07 and status['gPO'] == 3 and status['gSTA'] == 0


def test_activation_takes_gsta_0_1_3_and_delays_a_motion_request():
    g, _, _ = gripper()
    g.set_command(command(rACT=1, rGTO=1, rPR=100, rSP=255, rFR=150))  # SimpleController's 'a' + a position
    g.advance(0.02)
    status = g.status()
    assert (status['gACT'], status['gSTA'], status['gGTO'], status['gFLT']) == (1, 1, 0, 0x05)
    status = run_for(g, ACTIVATION - 0.1)
    assert status['gSTA'] == 1 and status['gPO'] == 3  # no motion while activating
    status = run_for(g, 0.2)
    assert status['gSTA'] == 3 and status['gFLT'] == 0 and status['gGTO'] == 1
    assert status['gOBJ'] == 0 and status['gCU'] > 0  # the delayed request runs now
    status = run_for(g, 1.0)
    assert (status['gPO'], status['gOBJ'], status['gPR'], status['gCU']) == (100, 3, 100, 0)


def test_motion_speed_follows_rsp_and_positions_beyond_the_ends_stop_there():
    g, _, _ = active()
    g.set_command(command(rACT=1, rGTO=1, rPR=255, rSP=255))
    assert run_for(g, 0.28)['gPO'] == pytest.approx(3 + 0.28 * 0.250 * 227 / 0.140, abs=1)
    status = run_for(g, 1.0)
    assert (status['gPO'], status['gOBJ'], status['gPR']) == (230, 3, 255)
    g.set_command(command(rACT=1, rGTO=1, rPR=0, rSP=0))  # slowest: 30 mm/s
    assert run_for(g, 1.0)['gPO'] == pytest.approx(230 - 0.030 * 227 / 0.140, abs=1)
    assert run_for(g, 5.0)['gPO'] == 3


def test_rgto_0_stops_the_fingers_where_they_are():
    g, _, _ = active()
    g.set_command(command(rACT=1, rGTO=1, rPR=230, rSP=255))
    moving = run_for(g, 0.2)
    assert moving['gOBJ'] == 0 and 3 < moving['gPO'] < 230
    g.set_command(command(rACT=1, rGTO=0, rPR=230, rSP=255))
    stopped = run_for(g, 0.5)
    assert stopped['gPO'] == pytest.approx(moving['gPO'], abs=2) and stopped['gGTO'] == 0
    # The manual: ignore gOBJ while gGTO is 0; 3 lets a client waiting for a stop see one.
    assert stopped['gCU'] == 0 and stopped['gOBJ'] == 3
    g.set_command(command(rACT=1, rGTO=1, rPR=230, rSP=255))  # go on
    assert run_for(g, 1.0)['gPO'] == 230


def test_closing_on_the_object_stops_at_its_width_with_gobj_2():
    g, _, _ = active(object_width=0.070)
    g.set_command(command(rACT=1, rGTO=1, rPR=255, rSP=255, rFR=255))
    status = run_for(g, 1.0)
    assert status['gOBJ'] == 2 and status['gPO'] == round(SPEC.scale.position(0.070))
    assert status['gCU'] == 80  # holding at full force
    g.set_command(command(rACT=1, rGTO=1, rPR=250, rSP=255, rFR=100))  # squeeze on: still held
    status = run_for(g, 0.5)
    assert status['gOBJ'] == 2 and status['gPO'] == round(SPEC.scale.position(0.070))
    g.set_command(command(rACT=1, rGTO=1, rPR=0, rSP=255))  # open: let go
    assert run_for(g, 0.1)['gOBJ'] == 0
    assert run_for(g, 1.0)['gOBJ'] == 3
    g.set_command(command(rACT=1, rGTO=1, rPR=50, rSP=255))  # wider than the object: no contact
    assert run_for(g, 1.0)['gOBJ'] == 3


class RockingFingers(gripper_sim.KinematicFingers):
    """Fingers on a part that rocks them, as a held can does under MuJoCo 3.2.3: once on it, every other
    cycle they read as moving, up to a count further closed; drop() lets the part slip out."""

    def __init__(self, spec, object_width):
        super(RockingFingers, self).__init__(spec, object_width)
        self.cycles_on_it = 0

    def advance(self, dt, at=None):
        motion = super(RockingFingers, self).advance(dt, at)
        if motion != gripper_sim.ON_OBJECT:
            return motion
        self.cycles_on_it += 1
        self.position = self.object_position + self.cycles_on_it % 2
        return gripper_sim.MOVING if self.cycles_on_it % 2 else motion

    def drop(self):
        self.object_position, self.motion = None, gripper_sim.MOVING


def test_a_part_rocking_in_the_fingers_stays_held_and_one_that_slips_out_is_lost():
    fingers = RockingFingers(SPEC, 0.070)
    g, _, _ = active(fingers=fingers)
    g.set_command(command(rACT=1, rGTO=1, rPR=255, rSP=255, rFR=255))
    run_for(g, 1.0)
    held = [run_for(g, 0.02) for _ in range(50)]
    assert fingers.cycles_on_it > 50
    assert {(s['gOBJ'], s['gCU']) for s in held} == {(2, 80)}
    on_it = SPEC.scale.position(0.070)
    assert all(on_it - 0.5 <= s['gPO'] <= on_it + 1.5 for s in held), held
    fingers.drop()  # the fingers close on at 250 mm/s: 3 mm on, within a cycle
    assert run_for(g, 0.02)['gOBJ'] == 0
    assert (run_for(g, 1.0)['gOBJ'], g.status()['gPO']) == (3, 230)


def test_auto_release_overrides_opens_slowly_and_needs_a_reset():
    g, _, _ = active(object_width=0.070)
    g.set_command(command(rACT=1, rGTO=1, rPR=255, rSP=255))
    run_for(g, 1.0)
    g.set_command(command(rACT=1, rATR=1))
    status = run_for(g, 0.5)
    assert (status['gFLT'], status['gSTA'], status['gGTO']) == (0x0B, 0, 0)
    assert status['gPO'] == pytest.approx(SPEC.scale.position(0.070) - 0.5 * 0.030 * 227 / 0.140, abs=1)
    g.set_command(command(rACT=1, rGTO=1, rPR=255, rSP=255))  # ignored while releasing
    status = run_for(g, 10.0)
    assert (status['gFLT'], status['gPO'], status['gSTA']) == (0x0F, 0, 0)  # at the mechanical end
    g.set_command(command(rACT=1, rGTO=1, rPR=255, rSP=255))
    assert run_for(g, 2.0)['gPO'] == 0  # no motion until reset and activated again
    g.set_command(command(rACT=0))
    assert g.status()['gFLT'] == 0 and g.status()['gACT'] == 0
    g.set_command(command(rACT=1, rGTO=1, rPR=100, rSP=255))
    assert run_for(g, ACTIVATION + 1.0)['gPO'] == 100


def test_reset_during_motion_stops_and_clears():
    g, _, _ = active()
    g.set_command(command(rACT=1, rGTO=1, rPR=230, rSP=255))
    run_for(g, 0.2)
    g.set_command(command(rACT=0, rGTO=1, rPR=230, rSP=255))
    status = run_for(g, 0.5)
    assert (status['gACT'], status['gSTA'], status['gGTO'], status['gOBJ']) == (0, 0, 0, 0)
    assert status['gFLT'] == 0x07  # rGTO without the activation bit


def test_nonsense_bits_are_taken_as_1_like_the_driver_with_one_warning_per_register_and_period():
    g, warn, clock = gripper()
    for _ in range(100):
        g.set_command(command(rACT=7, rGTO=200, rATR=0, rPR=80, rSP=255))
    assert g.command['rACT'] == 1 and g.command['rGTO'] == 1
    assert len(warn.lines) == 2 and 'rACT=7' in warn.lines[0] and 'rGTO=200' in warn.lines[1]
    status = run_for(g, ACTIVATION + 1.0)
    assert status['gSTA'] == 3 and status['gPO'] == 80
    clock.now += gripper_sim.RATE_LIMIT
    g.set_command(command(rACT=2, rGTO=1, rPR=80))
    assert len(warn.lines) == 3


def test_any_register_values_never_raise():
    g, _, _ = gripper(object_width=0.05)
    rng = np.random.default_rng(5)
    for values in rng.integers(0, 256, size=(3000, 6)):
        g.set_command(dict(zip(gripper_sim.COMMAND_FIELDS, values.tolist())))
        g.advance(float(rng.uniform(0, 0.1)))
        status = g.status()
        assert all(0 <= status[k] <= 255 for k in gripper_sim.STATUS_FIELDS), status


# -- gripper_joint_states parameters --------------------------------------------------------

def test_joint_states_calibration_defaults_and_override():
    scale = gripper_joint_states.scale_from_params(params())
    assert (scale.gpo_open, scale.gpo_closed, scale.stroke) == (3, 230, 0.140)
    scale = gripper_joint_states.scale_from_params(params(gpo_open=6, gpo_closed=227))
    assert scale.opening(6) == 0.140 and scale.opening(227) == 0.0


@pytest.mark.parametrize('values', [dict(gpo_open=230, gpo_closed=3), dict(gpo_closed=300),
                                    dict(gpo_open='a'), dict(gpo_open=-1)])
def test_joint_states_bad_calibration_is_one_line(values):
    with pytest.raises(sim_params.ParamError) as error:
        gripper_joint_states.scale_from_params(params(**values))
    assert str(error.value).startswith('~gpo_') and '\n' not in str(error.value)


def test_on_the_simulated_clock_a_readings_noise_is_fixed_by_its_time():
    settings = ft300_sim.FT300Settings.from_params(params())
    one, other = ft300_sim.SensorModel(settings), ft300_sim.SensorModel(settings)
    true = (0.0, 0.0, 9.5615, 0.0, 0.0, 0.0)
    forward = [one.read(true, index) for index in range(1000, 1600)]
    backward = [other.read(true, index) for index in reversed(range(1000, 1600))][::-1]
    assert forward == backward  # the same time, the same reading, in whatever order it is asked
    forces = np.array(forward)[:, :3] - true[:3]
    assert np.allclose(forces.std(axis=0), settings.noise_force, rtol=0.15)  # still the datasheet's noise
    assert one.read(true, 1000) != one.read(true, 1001)


class ScriptedCellLink(object):
    """The cell's side of the link as PhysicsFingers asks it, with the cell's time, fingers and kept samples
    set by the test: the order of events on the simulated clock, which a stepping cell leaves to chance."""

    info = {'gripper': {'min_opening': 0.0, 'max_opening': 0.1285, 'grip_force_range': (10.0, 125.0)}}

    def __init__(self):
        self.time, self.kept = 0.0, []
        self.state = dict(opening=0.1285, target=0.1285, motion=gripper_sim.AT_TARGET, grip_force=0.0)

    def finger(self, opening=None, speed=None, force=None):
        if opening is not None:
            self.state = dict(self.state, target=opening, motion=gripper_sim.MOVING)
        return self.time, dict(self.state)

    def finger_samples(self, period):
        kept, self.kept = self.kept, []
        return self.time, kept, 0, dict(self.state)


def test_a_status_due_at_the_commands_own_time_does_not_take_the_fingers_from_before_it():
    """The cell keeps the fingers at the end of the cycle that reaches a status's time; a command that
    arrives then follows that sample. The sample shows the fingers standing at the last target: taken as
    the new command's, a close would read as arrived (gOBJ 3 at the closed end) before it began."""
    spec = gripper_sim.spec_from_params(lambda name, default=None: default)
    cell = ScriptedCellLink()
    fingers = gripper_sim.PhysicsFingers(cell, spec, sample_period=0.02)
    cell.time = 0.04
    cell.kept = [(0.02, dict(cell.state)), (0.04, dict(cell.state))]  # open, at the open target
    fingers.go(spec.gpo_closed, spec.speed_counts(255), 1.0)  # at 0.04, after the cycle's sample
    assert fingers.advance(0.02, 0.04) == gripper_sim.MOVING
    cell.time = 0.06
    cell.kept = [(0.06, dict(cell.state, opening=0.12))]
    assert fingers.advance(0.02, 0.06) == gripper_sim.MOVING
    assert fingers.position == pytest.approx(spec.scale.position(0.12))
