"""A press straight down on the table: what MuJoCo's own contacts say about the sideways force the sensors read.

The arm is the simulated controller's core (ArmCore) on the physics cell, as the arm's node runs it,
running examples/force_mode_press.py's own program from the example's own start pose in the default
world; the FT 300 is zeroed in the air, as the example zeroes it. Over the second the example
averages, the truths are MuJoCo's contacts between the tool and the table: their summed force (the
impulse over the second), each contact's normal force and slip speed (the two bodies' relative
velocity at the contact point, in its tangent plane). From them:

- the FT 300's and the robot's own sideways force (both turned into base_link's axes) are the sideways
  force the contacts carry, within 0.3 N and 3 %: whatever pushes the tool sideways, the sensors read
  it, and nothing else;
- nothing slides (every tool contact under 1 mm/s) and the contact is symmetric (each pad carries
  40 to 60 % of the normal force): the example's press straight down, landing gently, then reads
  under 5 % of the normal force sideways, on the FT 300, the robot and the contacts; so does a press
  with x and y compliant at 0 N at the example's own landing speed;
- a planted lopsided contact (one pad 1 mm longer than the other) is seen as one: the check that
  finds the shipped press symmetric can fail.

The robot pushes along force_mode's compliant axes only: the servos' stiffness is per joint, and a
target running ahead of the tool straight down would otherwise pull across too (0.39 to 0.45 of the
normal force before force_mode.uncoupled; the gentle test fails without it). At the example's own
landing speed (5 cm/s) the press straight down reads 3 to 7 % sideways, left by the landing: the tool
pivots a little about its pads as they strike, they stick, and the held axes push back towards the
program's pose. doc/simulation.md says so; the first test measures and prints it.
"""
import math
import os
import types
import xml.etree.ElementTree as ElementTree

import numpy as np
import pytest
import rospkg

from ur3_ft_gripper_description import clients, kinematics
from ur3_ft_gripper_description.devices.physics.world import load_world
from ur3_ft_gripper_description.devices.ur_arm import core as arm_core
from ur3_ft_gripper_description.devices.ur_arm.physics_joints import PhysicsJointMotion
from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings
from ur3_ft_gripper_testing import shipped
from ur3_ft_gripper_testing.physics import START

force_mode_press = shipped.script('examples/force_mode_press.py')
PACKAGE_DIR = rospkg.RosPack().get_path('ur3_ft_gripper_description')
DEFAULT_WORLD = os.path.join(PACKAGE_DIR, 'config', 'worlds', 'default.yaml')
PADS = ('left_inner_finger_pad', 'right_inner_finger_pad')
FORCES = (10.0, 20.0, 40.0)
SLIDING = 0.001     # m/s: a tool contact slower than this sticks (measured: under 0.2 mm/s)
SHARE = (0.4, 0.6)  # each pad's part of the normal force in a symmetric contact (measured: 0.45 to 0.55)
SIDEWAYS = 0.05     # of the normal force: what a symmetric contact that does not slide may carry sideways
GENTLE = 0.005      # m/s: a landing that leaves no sideways push behind (measured: 2 to 4 % at 10 to 40 N)
# Of the normal force: what the example's own landing (5 cm/s) leaves sideways (measured 3 to 7 %); the
# servos' coupled pull that force_mode.uncoupled cancels made 39 to 45 %.
LANDED = 0.10
# The largest change of the FT 300's reading from one control cycle to the next over the second of a steady
# press: of the force, at least JUMP_FLOOR (N). Measured: 0.00 N with z compliant, up to 0.18 N with x, y
# and z (the press still sways slowly, 0.3 to 0.5 N over a quarter second). Integrated explicitly against
# the servos' damping, the admittance rang at half the CB3's control rate (19 N at 40 N); in the inverse
# kinematics' 10 um dead band it hunted, leaping 1 to 2 N.
JUMP, JUMP_FLOOR = 0.01, 0.2
COMPLIANT_XY = force_mode_press.PROGRAM.replace('[0, 0, 1, 0, 0, 0]', '[1, 1, 1, 0, 0, 0]')


def arm_settings(urdf, initial):
    config = os.path.join(rospkg.RosPack().get_path('ur_robot_driver'), 'config', 'ur3_controllers.yaml')
    values = {'~ur_type': 'ur3', '~controller_config_file': config, 'robot_description': urdf,
              '~controllers': 'joint_state_controller scaled_pos_joint_traj_controller',
              '~initial_positions': [float(q) for q in initial]}
    return read_settings(lambda name, default=None: values.get(name, default))


class Press(object):
    """The example's press on a cell of `mjcf_path`: run(program, force) -> what the sensors and contacts said."""

    def __init__(self, mjcf_path, urdf):
        from ur3_ft_gripper_description.devices.physics.cell import Cell
        tool = clients.ToolKinematics(types.SimpleNamespace(get_param=lambda name: urdf))
        x, y = force_mode_press.START_XY
        start = tool.path_to(list(START), x, y, force_mode_press.START_HEIGHT, force_mode_press.CLEAR_HEIGHT)[-1]
        self.settings = arm_settings(urdf, start)
        self.cell = Cell(mjcf_path, urdf, load_world(DEFAULT_WORLD), initial_arm=self.settings.initial)
        self.core = arm_core.ArmCore(self.settings, PhysicsJointMotion.from_settings(self.cell, self.settings))
        self.dt = 1.0 / self.settings.loop_hz
        model = kinematics.Model(urdf)
        self.base_axes = model.transform(model.root(), 'base')[:3, :3]  # the robot's base in base_link's axes
        m = self.cell.model
        self.table = m.geom('table').id
        self.pad_geoms = {m.geom(pad + '_collision_0').id: pad for pad in PADS}

    def cycles(self, seconds):
        for _ in range(int(round(seconds / self.dt))):
            self.core.step(self.dt)

    def tool_contacts(self):
        """[(pad, normal force N, slip speed m/s)] of every contact between a pad and the table now."""
        cell = self.cell
        m, d, mujoco = cell.model, cell.data, cell.mujoco
        rows, force = [], np.zeros(6)
        jacobians = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        for i in range(d.ncon):
            contact = d.contact[i]
            pair = {int(contact.geom1), int(contact.geom2)}
            pads = pair.intersection(self.pad_geoms)
            if self.table not in pair or not pads:
                continue
            mujoco.mj_contactForce(m, d, i, force)
            for jacobian, geom in zip(jacobians, (contact.geom1, contact.geom2)):
                mujoco.mj_jac(m, d, jacobian, None, contact.pos, m.geom_bodyid[geom])
            relative = (jacobians[1] - jacobians[0]).dot(d.qvel)
            normal = np.array(contact.frame[:3])
            slip = relative - normal * relative.dot(normal)
            rows.append((self.pad_geoms[pads.pop()], float(force[0]), float(np.linalg.norm(slip))))
        return rows

    def run(self, program, force, speed=0.05):
        """The program pressing with `force` (N), landing at `speed` (m/s), the FT 300 zeroed in the air
        before; the readings averaged over the example's second (dict, forces in base_link's axes)."""
        cell = self.cell
        self.cycles(1.0)
        zero = np.array(cell.wrench())
        # The example's time to settle, after the time its descent takes at this speed beyond its own.
        settle = force_mode_press.SETTLE + force_mode_press.START_HEIGHT * (1.0 / speed - 1.0 / 0.05)
        self.core.script_command(program.format(force=force, speed=speed, seconds=settle + 2.0))
        assert self.core.script_running, self.core.take_messages()
        self.cycles(settle)
        ft300, robot, shares, slip = [], [], {pad: 0.0 for pad in PADS}, 0.0
        began, impulse = cell.time, cell.contact_impulse()
        pads_before = [cell.body_pose(pad)[0] for pad in PADS]
        for _ in range(int(round(force_mode_press.MEASURE / self.dt))):
            self.core.step(self.dt)
            sensor = cell.body_pose(cell.ft_frame)[1]
            ft300.append(sensor.dot((np.array(cell.wrench()) - zero)[:3]))
            robot.append(self.base_axes.dot(self.core.tcp_force()[0][:3]))
            for pad, normal, speed in self.tool_contacts():
                shares[pad] += normal
                slip = max(slip, speed)
        assert cell.protective_stop is None, cell.protective_stop
        moved = max(np.linalg.norm(cell.body_pose(pad)[0] - before) for pad, before in zip(PADS, pads_before))
        total = sum(shares.values())
        return dict(ft300=np.mean(ft300, axis=0), robot=np.mean(robot, axis=0),
                    jump=np.max(np.abs(np.diff(np.array(ft300)[:, 2]))),
                    contact=(cell.contact_impulse() - impulse) / (cell.time - began),
                    shares={pad: value / total if total else 0.0 for pad, value in shares.items()},
                    slip=slip, moved=moved)


def sideways(force):
    return float(np.hypot(force[0], force[1]))


def symmetric(result):
    return all(SHARE[0] <= share <= SHARE[1] for share in result['shares'].values())


def describe(force, result):
    return ('%g N: sideways FT 300 %.2f, robot %.2f, contacts %.2f N of %.2f N normal (FT 300 jumps up to %.2f N); '
            'pads %s; slip %.2f mm/s, pads moved %.3f mm' % (
                force, sideways(result['ft300']), sideways(result['robot']), sideways(result['contact']),
                result['contact'][2], result['jump'], ', '.join('%.2f' % s for s in result['shares'].values()),
                result['slip'] * 1e3, result['moved'] * 1e3))


def check_sensors(force, result):
    """The FT 300 and the robot read the contacts' force, sideways and along z."""
    contact, text = result['contact'], describe(force, result)
    tolerance = 0.3 + 0.03 * sideways(contact)
    for reading in (result['ft300'], result['robot']):
        assert np.linalg.norm((reading - contact)[:2]) < tolerance, text
        assert reading[2] == pytest.approx(contact[2], rel=0.05, abs=0.5), text
    assert contact[2] == pytest.approx(force, rel=0.05, abs=0.5), text
    # A steady press reads steady, cycle by cycle: not a force ringing about the right mean.
    assert result['jump'] < max(JUMP * force, JUMP_FLOOR), text


@pytest.fixture
def press(mujoco, robot):
    return lambda mjcf_path=robot[0]: Press(mjcf_path, robot[1])


def check_straight(result, force):
    """Nothing slides, both pads alike, and under 5 % of the normal force sideways on every reading."""
    assert result['slip'] < SLIDING and result['moved'] < 1e-4, describe(force, result)
    assert symmetric(result), describe(force, result)
    for reading in (result['ft300'], result['robot'], result['contact']):
        assert sideways(reading) < SIDEWAYS * result['contact'][2], describe(force, result)


@pytest.mark.parametrize('force', FORCES)
def test_pressing_straight_down_the_sensors_read_the_sideways_force_the_contacts_carry(press, force):
    result = press().run(force_mode_press.PROGRAM, force)
    print('z compliant: ' + describe(force, result))
    check_sensors(force, result)
    # The tool sticks where it landed, pivoted a little about its pads (which then share the load
    # unevenly, measured 0.57 to 0.61): the sideways force is static friction, what the landing left.
    assert result['slip'] < SLIDING and result['moved'] < 1e-4, describe(force, result)
    for reading in (result['ft300'], result['robot'], result['contact']):
        assert sideways(reading) < LANDED * result['contact'][2], describe(force, result)


@pytest.mark.parametrize('force', FORCES)
def test_pressing_straight_down_after_a_gentle_landing_reads_under_5_percent_sideways(press, force):
    # The example's own program: only z compliant, the other axes held at the program's pose.
    result = press().run(force_mode_press.PROGRAM, force, speed=GENTLE)
    print('z compliant, landing at %g m/s: %s' % (GENTLE, describe(force, result)))
    check_sensors(force, result)
    check_straight(result, force)


@pytest.mark.parametrize('force', FORCES)
def test_a_symmetric_press_that_does_not_slide_reads_under_5_percent_sideways(press, force):
    # x and y compliant at 0 N: nothing but the contact decides the sideways force.
    result = press().run(COMPLIANT_XY, force)
    print('x, y, z compliant: ' + describe(force, result))
    check_sensors(force, result)
    check_straight(result, force)


def lopsided(mjcf_path, folder):
    """The model of `mjcf_path` with the left pad's collision box 1 mm longer (0.5 mm at each end)."""
    tree = ElementTree.parse(mjcf_path)
    for geom in tree.getroot().iter('geom'):
        if geom.get('name') == PADS[0] + '_collision_0':
            size = [float(v) for v in geom.get('size').split()]
            size[1] += 0.0005
            geom.set('size', ' '.join(repr(v) for v in size))
    path = os.path.join(folder, 'lopsided.xml')
    tree.write(path)
    return path


def test_a_planted_lopsided_contact_is_caught(press, robot, tmp_path):
    force = 20.0
    result = press(lopsided(robot[0], str(tmp_path))).run(COMPLIANT_XY, force)
    print('lopsided, x, y, z compliant: ' + describe(force, result))
    check_sensors(force, result)
    assert not symmetric(result), 'a pad 1 mm longer than the other went unseen: ' + describe(force, result)
    assert max(result['shares'].values()) > 0.9, describe(force, result)


def test_the_lopsided_model_differs_only_in_that_pad(robot, tmp_path):
    """The planted fault is what it says: one geom's length, the rest of the model as exported."""
    planted = ElementTree.parse(lopsided(robot[0], str(tmp_path))).getroot()
    original = ElementTree.parse(robot[0]).getroot()
    changed = [(a.get('name'), a.get('size'), b.get('size')) for a, b in zip(original.iter('geom'), planted.iter('geom'))
               if a.attrib != b.attrib]
    assert len(changed) == 1 and changed[0][0] == PADS[0] + '_collision_0', changed
    assert math.isclose(float(changed[0][2].split()[1]) - float(changed[0][1].split()[1]), 0.0005, abs_tol=1e-12)
