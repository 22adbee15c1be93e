"""The physics cell's arm, mass, safety and clock against the model's figures and the robot's behaviour.

Known truths: the masses of ur_description and of Robotiq's manual, the gravity torques the
URDF's masses make at a pose (its own forward kinematics), commanded speeds, the servoj lag law
of the kinematic simulation, the force limit of the protective stop, and the FT 300's samples
counted in whole timesteps of simulated time.
"""
import ast
import math
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np
import pytest
import rospkg
import yaml

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices.physics.world import load_world
from ur3_ft_gripper_description.devices.ur_arm import joints
from ur3_ft_gripper_description.devices.ur_arm.joints import JointCommand
from ur3_ft_gripper_description.model import description, export, inertials, mjcf
from ur3_ft_gripper_testing.physics import ARM_JOINTS, START, STANDARD_GRAVITY, TABLE, Arm, close_on

PACKAGE_DIR = rospkg.RosPack().get_path('ur3_ft_gripper_description')


def manual_total_mass():
    """ur_description's UR3 links plus Robotiq's FT 300 + 2F-140 (config/robotiq_mass.yaml)."""
    path = os.path.join(rospkg.RosPack().get_path('ur_description'), 'config', 'ur3', 'physical_parameters.yaml')
    with open(path) as f:
        inertia = yaml.safe_load(f)['inertia_parameters']
    arm = sum(inertia['%s_mass' % link] for link in
              ('base', 'shoulder', 'upper_arm', 'forearm', 'wrist_1', 'wrist_2', 'wrist_3'))
    with open(os.path.join(PACKAGE_DIR, 'config', 'robotiq_mass.yaml')) as f:
        robotiq = yaml.safe_load(f)['ft300_with_2f140']['mass']
    return arm + robotiq


def test_the_robots_mass_is_the_models_and_the_manuals(make_cell, robot):
    cell = make_cell('', START)
    simulated = float(np.sum(cell.model.body_mass[cell.robot_bodies]))
    urdf = sum(link.inertial.mass for link in kinematics.Model(robot[1]).robot.links if link.inertial)
    assert simulated == pytest.approx(urdf, rel=1e-9)
    assert simulated == pytest.approx(manual_total_mass(), rel=0.02)


def gravity_torques(urdf_text, arm):
    """Each arm joint's torque holding the links below it against gravity (the URDF's masses, its FK)."""
    model = kinematics.Model(urdf_text)
    positions = dict(zip(ARM_JOINTS, arm))
    torques = []
    for name in ARM_JOINTS:
        joint = model.joints[name]
        frame = model.transform(model.root(), joint.child, positions)  # at the joint, in its axes
        own = model.robot.link_map[joint.child].inertial
        mass, com = inertials.combine_masses([inertials.mass_below(model, joint.child, positions),
                                              (own.mass, kinematics.pose_matrix(own.origin)[:3, 3])])
        lever = frame[:3, :3].dot(com)
        axis = frame[:3, :3].dot(joint.axis)
        torques.append(-float(np.cross(lever, [0.0, 0.0, -mass * STANDARD_GRAVITY]).dot(axis)))
    return np.array(torques)


@pytest.mark.parametrize('offset', [[0.0] * 6, [0.5, 0.3, -0.4, 0.6, 0.8, 0.2]], ids=['start', 'other'])
def test_at_rest_the_efforts_hold_the_models_weight(make_cell, robot, offset):
    arm = START + np.array(offset)
    cell = make_cell('', arm)
    Arm(cell).hold(1.0)
    expected = gravity_torques(robot[1], arm)
    assert np.allclose(cell.arm_effort, expected, atol=0.01 + 0.005 * np.max(np.abs(expected))), (
        cell.arm_effort, expected)
    assert np.max(np.abs(cell.arm_position - arm)) < 1e-4  # it holds the start pose: no sag


def test_hold_keeps_the_start_pose_and_never_teleports(make_cell):
    cell = make_cell('', START)
    motion = Arm(cell).motion
    assert np.array_equal(motion.position, START)
    for _ in range(500):
        motion.step(JointCommand('HOLD'), 0.002)
        assert np.max(np.abs(motion.position - START)) < 1e-4
    # A far command: the reference leaves for it at the joints' velocity limits at once, and the
    # arm after it, from where it is, never jumping: catching up with a reference that took no
    # time to accelerate, the servo overshoots the limits for a while (measured: up to 1.6 times),
    # where a teleport would move a joint by the whole distance. Streamed trajectories accelerate,
    # and the arm stays on them (the servo test below).
    far = START + np.array([1.0, 0.5, -0.5, 1.0, 1.0, 2.0])
    previous = motion.position
    for _ in range(1500):
        motion.step(JointCommand('MOVE', far), 0.002)
        assert np.all(np.abs(motion.position - previous) <= cell.arm_velocity_limits * 0.002 * 2.0)
        previous = motion.position
    assert np.max(np.abs(motion.position - far)) < 1e-3


def test_velocity_commands_move_the_joints_at_that_speed(make_cell):
    cell = make_cell('', START)
    motion = Arm(cell).motion
    speed = np.array([0.2, -0.1, 0.15, 0.3, -0.3, 0.5])
    for _ in range(250):
        motion.step(JointCommand('VELOCITY', velocity=speed), 0.002)
    before, time = motion.position, cell.time
    for _ in range(250):
        motion.step(JointCommand('VELOCITY', velocity=speed), 0.002)
    assert np.allclose((motion.position - before) / (cell.time - time), speed, rtol=0.01, atol=1e-3)
    assert np.allclose(motion.velocity, speed, rtol=0.02, atol=2e-3)


def test_servo_follows_streamed_positions_with_servojs_lag(make_cell):
    """Positions streamed at 500 Hz along a sine: the joints follow the kinematic simulation's lag law."""
    cell = make_cell('', START)
    motion = Arm(cell).motion
    amplitude = np.array([0.2, 0.1, -0.15, 0.3, 0.3, 0.5])
    expected = START.copy()
    worst = 0.0
    for k in range(1, 1001):
        stream = START + amplitude * math.sin(2.0 * math.pi * 0.5 * k * 0.002)
        motion.step(JointCommand('SERVO', stream), 0.002)
        expected, _ = joints.follow(expected, stream, 0.002, motion.lookahead, cell.arm_velocity_limits,
                                    cell.arm_lower, cell.arm_upper)
        worst = max(worst, float(np.max(np.abs(motion.position - expected))))
    assert worst < 0.0005, 'the servo strayed %.4f rad from the lag law' % worst


@pytest.fixture(scope='module')
def make_cell_without_ft300(mujoco, tmp_path_factory):
    """make_cell_without_ft300(world text) -> a Cell of the UR3 with the 2F-140 on its flange, no FT 300."""
    from ur3_ft_gripper_description.devices.physics.cell import Cell
    folder = tempfile.mkdtemp(prefix='ur3_ft_gripper_physics_')
    mappings = export.model_mappings(ft_sensor=False)
    doc = description.expand_model(mappings)
    path = os.path.join(folder, 'robot.xml')
    mjcf.write_mjcf(doc, mappings, path)
    urdf = description.to_xml(doc)

    def make(world_text):
        world = tmp_path_factory.mktemp('world') / 'world.yaml'
        world.write_text(world_text)
        return Cell(path, urdf, load_world(str(world)), initial_arm=START)
    yield make
    shutil.rmtree(folder, ignore_errors=True)


@pytest.mark.parametrize('ft300', [True, False], ids=['with_the_ft300', 'without_it'])
def test_pushing_into_the_table_reports_a_protective_stop_and_the_arm_stops_pressing(make_cell,
                                                                                     make_cell_without_ft300, ft300):
    """The joint-motion seam's side: the step in which the contact force passed 150 N reports it (the
    core latches it, test below); the cell then holds the arm where it stopped, so the force drops.
    Without the FT 300, whose force sensor made MuJoCo compute the bodies' contact forces, the same."""
    cell = make_cell(TABLE, START) if ft300 else make_cell_without_ft300(TABLE)
    arm = Arm(cell)
    close_on(cell, 60.0, speed=0.25)
    forces, reasons = [], []

    def stopped():
        forces.append(float(np.linalg.norm(cell.contact_force())))
        reasons.append(arm.motion.protective_stop)
        return arm.motion.protective_stop is not None
    assert arm.move_tool([0.0, 0.0, -0.12], 3.0, until=stopped), 'no protective stop'
    assert 'exceeded the 150 N limit' in reasons[-1]
    assert max(forces) > 150.0 and not any(reasons[:-1])
    held = cell.arm_position
    for _ in range(500):  # what the core commands meanwhile
        arm.motion.step(JointCommand('HOLD', held), 0.002)
        assert arm.motion.protective_stop is None, 'the stop is reported by the step that caused it only'
    assert np.max(np.abs(cell.arm_position - held)) < 0.002, 'the arm moved during the protective stop'
    assert np.linalg.norm(cell.contact_force()) < 150.0
    assert arm.move_tool([0.0, 0.0, 0.05], 1.0) is False
    assert np.linalg.norm(cell.contact_force()) < 1.0, 'the arm did not lift off'


def test_the_core_on_physics_latches_the_stop_as_the_robot_does(make_cell, robot):
    """ArmCore over PhysicsJointMotion: twist_controller pushes the tool into the table; the robot enters
    PROTECTIVE_STOP, pauses its program and holds, refuses to unlock for 5 s (Dashboard Server manual),
    and moves again after 'unlock protective stop' and 'play'."""
    from ur3_ft_gripper_description.devices.ur_arm import controller_manager as cm
    from ur3_ft_gripper_description.devices.ur_arm import core as arm_core
    from ur3_ft_gripper_description.devices.ur_arm import robot_state as rs
    from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings
    from ur3_ft_gripper_description.devices.ur_arm.physics_joints import PhysicsJointMotion
    config = os.path.join(rospkg.RosPack().get_path('ur_robot_driver'), 'config', 'ur3_controllers.yaml')
    values = {'~ur_type': 'ur3', '~controller_config_file': config, 'robot_description': robot[1],
              '~controllers': 'joint_state_controller scaled_pos_joint_traj_controller'}
    settings = read_settings(lambda name, default=None: values.get(name, default))
    cell = make_cell(TABLE, settings.initial)
    core = arm_core.ArmCore(settings, PhysicsJointMotion.from_settings(cell, settings))
    dt = 1.0 / settings.loop_hz  # 125 Hz: four steps of the cell a cycle
    assert core.switch_controllers(['twist_controller'], ['scaled_pos_joint_traj_controller'], cm.STRICT)[0]
    core.twist_command('twist_controller', [0.0, 0.0, -0.05, 0.0, 0.0, 0.0])
    for _ in range(int(3.0 / dt)):
        snapshot = core.step(dt)
        if snapshot.safety_mode == rs.PROTECTIVE_STOP:
            break
    assert snapshot.safety_mode == rs.PROTECTIVE_STOP, 'no protective stop'
    assert core.robot.program_state == rs.PAUSED and snapshot.program_running
    assert any('Protective stop' in text and '150 N' in text for _, text in core.take_messages())
    held = cell.arm_position
    for _ in range(int(1.0 / dt)):
        core.step(dt)
    assert np.max(np.abs(cell.arm_position - held)) < 0.002, 'the arm moved during the protective stop'
    assert np.linalg.norm(cell.contact_force()) < 150.0
    assert core.dashboard('unlock protective stop') == rs.UNLOCK_TOO_EARLY
    for _ in range(int(4.5 / dt)):
        core.step(dt)
    assert core.dashboard('unlock protective stop') == 'Protective stop releasing'
    core.twist_command('twist_controller', [0.0, 0.0, 0.05, 0.0, 0.0, 0.0])
    assert core.dashboard('play') == 'Starting program'
    height = cell.body_pose(cell.gripper_base)[0][2]
    for _ in range(int(1.0 / dt)):
        snapshot = core.step(dt)
    assert snapshot.safety_mode == rs.SAFETY_NORMAL
    assert cell.body_pose(cell.gripper_base)[0][2] > height + 0.03, 'the tool did not rise after play'
    assert np.linalg.norm(cell.contact_force()) < 1.0, 'the arm did not lift off'


def test_the_default_world_loads_with_objects_the_gripper_can_hold(make_cell):
    with open(os.path.join(PACKAGE_DIR, 'config', 'worlds', 'default.yaml')) as f:
        text = f.read()
    cell = make_cell(text, START)
    assert len(cell.objects) >= 2
    start = {name: cell.object_pose(name)[0] for name in cell.objects}
    cell.step(1.0)
    for name in cell.objects:
        solid = cell.world.by_name(name)
        narrowest = min(solid.size[:2]) if solid.shape == 'box' else solid.size[0]
        assert narrowest < cell.gripper.max_opening, name
        assert np.linalg.norm(cell.object_pose(name)[0] - start[name]) < 0.001, name  # resting
        reach = math.hypot(*start[name][:2])
        assert reach < 0.45, '%s is %.2f m from the base: beyond the UR3 with the tool down' % (name, reach)


FT_FRAME = 'robotiq_ft_frame_id'
WRENCH_PERIOD = 0.01  # the FT 300's 100 Hz


def hanging_weight(urdf_text):
    """The tool side's weight (N) on the FT 300: the URDF's masses below its sensor frame."""
    mass, _ = inertials.mass_below(kinematics.Model(urdf_text), FT_FRAME)
    return mass * STANDARD_GRAVITY


def timesteps(cell, samples):
    """The whole number of timesteps of each sample's time."""
    return [int(round(t / cell.timestep)) for t, _, _ in samples]


@pytest.mark.parametrize('calls', [(0.008,), (0.002,), (0.003, 0.0131, 0.0039)],
                         ids=['cb3_8ms', 'e_series_2ms', 'late_and_irregular'])
def test_wrench_samples_come_one_per_period_of_simulated_time_each_the_hanging_grippers_weight(
        make_cell, robot, calls):
    """Two simulated seconds, whatever the calls of step() and however seldom they are taken: 200
    samples, stamped exactly 5 timesteps apart (in whole timesteps, no float drift), none lost or
    twice, each the 2F-140's weight hanging below the FT 300 (the URDF's masses)."""
    cell = make_cell('', START)
    Arm(cell).hold(1.0)  # at rest; 1 s is a whole multiple of 10 ms
    first = int(round(cell.time / cell.timestep))
    assert cell.time == first * cell.timestep
    cell.keep_wrench_samples(WRENCH_PERIOD)
    samples = []
    for k in range(int(round(2.0 / sum(calls))) * len(calls)):
        cell.step(calls[k % len(calls)])
        if k % 7 == 6:  # a node that asks now and then
            taken, dropped = cell.take_wrench_samples()
            assert dropped == 0
            samples += taken
    taken, dropped = cell.take_wrench_samples()
    samples += taken
    assert dropped == 0 and len(samples) == 200
    assert timesteps(cell, samples) == list(range(first + 5, first + 1001, 5))
    assert [t for t, _, _ in samples] == [n * cell.timestep for n in timesteps(cell, samples)]
    assert samples[-1][0] == cell.time
    weight = hanging_weight(robot[1])
    for _, (fx, fy, fz, tx, ty, tz), acceleration in samples:
        assert fz == pytest.approx(weight, rel=0.005) and abs(fx) < 0.01 and abs(fy) < 0.01
        # The sensor points down and holds still: its accelerometer reads gravity's reaction along -z.
        assert np.allclose(acceleration, (0.0, 0.0, -STANDARD_GRAVITY), atol=0.01 * STANDARD_GRAVITY)
    assert samples[-1][1] == tuple(cell.wrench())  # the last one is the reading of its time
    assert samples[-1][2] == tuple(cell.accelerometer())


def test_each_wrench_sample_is_the_reading_at_its_own_timestep(make_cell):
    """The fingers closing shake the tool side, so the reading changes at every timestep: a cell stepped
    in 8 ms calls (a CB3's; 10 ms falls inside them) keeps at every 10 ms exactly the reading that the
    same cell stepped one timestep a call shows at that time."""
    keeping, reading = make_cell('', START), make_cell('', START)
    for cell in (keeping, reading):
        cell.command_finger(0.0, 0.15, 60.0)
    keeping.keep_wrench_samples(WRENCH_PERIOD)
    readings = {}
    for _ in range(75):  # 0.6 s, the fingers moving all along
        keeping.step(0.008)
        for _ in range(4):
            reading.step(0.002)
            readings[int(round(reading.time / reading.timestep))] = (tuple(reading.wrench()),
                                                                      tuple(reading.accelerometer()))
    samples, dropped = keeping.take_wrench_samples()
    assert dropped == 0 and timesteps(keeping, samples) == list(range(5, 301, 5))
    assert [(wrench, acceleration) for _, wrench, acceleration in samples] == [readings[n] for n in range(5, 301, 5)]
    assert all(readings[n] != readings[n - 1] for n in range(5, 301, 5)), 'one timestep off would go unseen'


def test_beyond_their_bound_the_oldest_wrench_samples_are_dropped_and_counted(make_cell):
    cell = make_cell('', START)
    cell.keep_wrench_samples(WRENCH_PERIOD, keep=50)
    cell.step(1.0)  # 100 samples
    samples, dropped = cell.take_wrench_samples()
    assert dropped == 50 and timesteps(cell, samples) == list(range(255, 501, 5))  # the newest 50
    cell.step(0.1)
    samples, dropped = cell.take_wrench_samples()
    assert dropped == 0 and timesteps(cell, samples) == list(range(505, 551, 5))
    cell.keep_wrench_samples(2 * WRENCH_PERIOD)  # another period: kept anew from now
    cell.step(0.1)
    samples, dropped = cell.take_wrench_samples()
    assert dropped == 0 and timesteps(cell, samples) == list(range(560, 601, 10))


@pytest.mark.parametrize('period', [0.003, 0.0101, 0.0, -0.01, float('nan')])
def test_a_wrench_sample_period_of_no_whole_number_of_timesteps_is_refused_in_one_line(make_cell, period):
    cell = make_cell('', START)
    with pytest.raises(ValueError) as raised:
        cell.keep_wrench_samples(period)
    text = str(raised.value)
    assert repr(period) in text and repr(cell.timestep) in text and '\n' not in text
    with pytest.raises(ValueError) as raised:
        cell.take_wrench_samples()
    assert 'keep_wrench_samples' in str(raised.value)


def test_without_the_ft300_wrench_samples_are_refused_as_the_wrench_is(make_cell_without_ft300):
    cell = make_cell_without_ft300('')
    for ask in (cell.wrench, lambda: cell.keep_wrench_samples(WRENCH_PERIOD)):
        with pytest.raises(ValueError) as raised:
            ask()
        assert str(raised.value) == 'the model has no FT 300'


def run_python(code):
    return subprocess.run([sys.executable, '-c', code], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, timeout=120)


def test_without_mujoco_physics_says_so_in_one_line_with_the_install_command():
    code = ('import sys; sys.modules["mujoco"] = None\n'
            'from ur3_ft_gripper_description.devices.physics import MissingMuJoCo\n'
            'from ur3_ft_gripper_description.devices.physics.cell import Cell\n'
            'try:\n    Cell.build()\nexcept MissingMuJoCo as exc:\n    print(exc)\n')
    run = run_python(code)
    assert run.returncode == 0, run.stderr
    lines = run.stdout.strip().splitlines()
    assert len(lines) == 1 and 'pip install mujoco' in lines[0] and 'python3-mujoco-pip' in lines[0], run.stdout


def test_the_kinematic_simulation_never_imports_mujoco():
    """Only the physics package imports MuJoCo, inside a function; importing any module imports none."""
    source = os.path.join(PACKAGE_DIR, 'src', 'ur3_ft_gripper_description')
    importers = []
    for folder, _, files in os.walk(source):
        for name in files:
            if name.endswith('.py'):
                path = os.path.join(folder, name)
                with open(path) as f:
                    tree = ast.parse(f.read(), path)
                for node in ast.walk(tree):
                    names = ([alias.name for alias in node.names] if isinstance(node, ast.Import) else
                             [node.module] if isinstance(node, ast.ImportFrom) else [])
                    if any(n and n.split('.')[0] == 'mujoco' for n in names):
                        importers.append((os.path.relpath(path, source), node.col_offset))
    assert importers == [('devices/physics/__init__.py', 8)], importers  # indented: in require_mujoco
    modules = [os.path.relpath(os.path.join(folder, name), source)[:-3].replace(os.sep, '.')
               for folder, _, files in os.walk(source) for name in files
               if name.endswith('.py') and name != '__init__.py']
    code = ('import importlib, sys\n'
            'for module in %r:\n'
            '    try:\n'
            '        importlib.import_module("ur3_ft_gripper_description." + module)\n'
            '    except ImportError as exc:\n'
            '        if "mujoco" in str(exc): raise\n'
            'print("mujoco" in sys.modules)\n' % sorted(modules))
    run = run_python(code)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == 'False'
