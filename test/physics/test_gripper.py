"""The 2F-140 on physics: grasps against the objects' widths, its grip force, its linkage and its hold.

Known truths: an object's width (through the model's own opening mapping, GripperKinematics;
the register scale's side is test_gripper_registers.py's), the grip force asked for (against the
normal force of MuJoCo's contact solver), the linkage's own forward kinematics, and a held
object's position between the pads.
"""
import math

import numpy as np
import pytest

from ur3_ft_gripper_description.devices.physics.cell import AT_TARGET, ON_OBJECT
from ur3_ft_gripper_description.number_text import number_list
from ur3_ft_gripper_testing.grasp import GAP_TOLERANCE
from ur3_ft_gripper_testing.physics import START, Arm, close_on, in_gripper

# The creep limit: a held object hanging still may slip by less than this (m/s).
CREEP_LIMIT = 17e-6


def hexagonal_prism(path, across_flats, height):
    """An OBJ file of a hexagonal prism standing on its base, two of its faces `across_flats` apart along y."""
    radius = across_flats / math.sqrt(3.0)
    ring = [(radius * math.cos(k * math.pi / 3.0), radius * math.sin(k * math.pi / 3.0)) for k in range(6)]
    lines = ['v %s' % number_list((x, y, z), ' ') for z in (0.0, height) for x, y in ring]
    lines += ['f 1 %d %d' % (k + 1, k) for k in range(2, 6)]   # bottom, facing down
    lines += ['f 7 %d %d' % (k + 6, k + 7) for k in range(2, 6)]    # top, facing up
    for k in range(1, 7):
        nxt = k % 6 + 1
        lines += ['f %d %d %d' % (k, nxt, nxt + 6), 'f %d %d %d' % (k, nxt + 6, k + 6)]
    path.write_text('\n'.join(lines) + '\n')
    return str(path)


# (id, world arguments, width between the pads in m): different widths and shapes within the stroke.
GRASPS = [
    ('box_30mm', dict(width=0.03), 0.03),
    ('box_50mm', dict(width=0.05), 0.05),
    ('cylinder_80mm', dict(width=0.08, shape='cylinder'), 0.08),
    ('box_100mm', dict(width=0.10, mass=0.5), 0.10),
]


@pytest.mark.parametrize('world,width', [g[1:] for g in GRASPS], ids=[g[0] for g in GRASPS])
def test_closing_stops_on_the_object_at_its_width(make_cell, between_pads, world, width):
    cell = make_cell(between_pads(**world), START)
    state = close_on(cell, 60.0, speed=0.15)
    assert state.motion == ON_OBJECT and state.closing, state
    assert state.opening == pytest.approx(width, abs=GAP_TOLERANCE), state
    assert cell.gripper.opening(state.angle) == state.opening


def test_a_mesh_object_stops_the_fingers_at_its_width(make_cell, between_pads, tmp_path):
    prism = hexagonal_prism(tmp_path / 'hexagon.obj', 0.07, 0.12)
    cell = make_cell(between_pads(0.07, shape='mesh', mesh=prism, height=0.12), START)
    state = close_on(cell, 60.0, speed=0.15)
    assert state.motion == ON_OBJECT, state
    assert state.opening == pytest.approx(0.07, abs=0.001), state


@pytest.mark.parametrize('target', [0.0, 0.04, 0.09])
def test_closing_on_nothing_reaches_the_request_and_opening_reaches_the_open_end(make_cell, target):
    cell = make_cell('', START)
    cell.command_finger(target, 0.25, 125.0)
    cell.step(1.0)
    state = cell.finger()
    assert state.motion == AT_TARGET, state
    assert state.opening == pytest.approx(target, abs=0.0005)
    cell.command_finger(1.0, 0.25, 125.0)  # wider than the model opens: the open end
    cell.step(1.0)
    state = cell.finger()
    assert state.motion == AT_TARGET and state.opening == pytest.approx(cell.gripper.max_opening, abs=1e-4)


def test_the_fingers_move_at_the_speed_asked_for(make_cell):
    cell = make_cell('', START)
    cell.command_finger(0.0, 0.05, 125.0)
    cell.step(0.2)
    before, time = cell.finger().opening, cell.time
    cell.step(1.0)
    assert (before - cell.finger().opening) / (cell.time - time) == pytest.approx(0.05, rel=0.01)


def pad_normal_forces(cell):
    """Normal force (N) of MuJoCo's contacts on each pad."""
    forces = {}
    for i in range(cell.data.ncon):
        contact = cell.data.contact[i]
        for geom in (contact.geom1, contact.geom2):
            body = cell.model.body(cell.model.geom_bodyid[geom]).name
            if body.endswith('inner_finger_pad'):
                local = np.zeros(6)
                cell.mujoco.mj_contactForce(cell.model, cell.data, i, local)
                forces[body] = forces.get(body, 0.0) + local[0]
    return forces


@pytest.mark.parametrize('force', [10.0, 60.0, 125.0])
def test_the_pads_squeeze_with_the_force_asked_for(make_cell, between_pads, force):
    """Lifted off the table, so that only the pads hold the object sideways; light, because the
    pads rise along an arc as they close, and the friction that holds an object's weight then
    adds to their squeeze (0.3 kg: 4 % of 10 N)."""
    cell = make_cell(between_pads(0.05, mass=0.05), START)
    assert close_on(cell, force).motion == ON_OBJECT
    Arm(cell).move_tool([0.0, 0.0, 0.05], 0.5)
    cell.step(0.5)
    pads = pad_normal_forces(cell)
    assert sorted(pads) == ['left_inner_finger_pad', 'right_inner_finger_pad']
    for body, normal in pads.items():
        assert normal == pytest.approx(force, rel=0.02), (body, pads)
    assert cell.finger().grip_force == pytest.approx(force, rel=0.01)


def linkage_drift(cell):
    """Largest distance (m) between a pad where MuJoCo has it and where the linkage's law puts it."""
    base, rotation = cell.body_pose(cell.gripper_base)
    laws = cell.gripper.pad_poses(cell.finger().angle)
    worst = 0.0
    for pad, law in zip(('left_inner_finger_pad', 'right_inner_finger_pad'), laws):
        position = cell.body_pose(pad)[0]
        worst = max(worst, float(np.linalg.norm(rotation.T.dot(position - base) - law[:3, 3])))
    return worst


def test_the_closed_linkage_drifts_less_than_a_millimetre_over_100000_steps(make_cell, between_pads):
    """Squeezing a 1 kg object with the full grip force, lifted: the linkage's heaviest load."""
    cell = make_cell(between_pads(0.05), START)
    assert close_on(cell, 125.0).motion == ON_OBJECT
    Arm(cell).move_tool([0.0, 0.0, 0.1], 1.0)
    worst, steps = 0.0, 0
    while steps < 100000:
        steps += cell.step(100 * cell.timestep)
        worst = max(worst, linkage_drift(cell))
    print('linkage drift over %d steps: %.3f mm' % (steps, worst * 1e3))
    assert worst < 0.001, 'the linkage drifted %.3f mm' % (worst * 1e3)


@pytest.mark.parametrize('force', [20.0, 125.0])
def test_a_held_kilogram_hanging_still_creeps_less_than_17_um_per_s(make_cell, between_pads, force):
    cell = make_cell(between_pads(0.05, mass=1.0), START)
    arm = Arm(cell)
    assert close_on(cell, force).motion == ON_OBJECT
    arm.move_tool([0.0, 0.0, 0.15], 1.5)
    arm.hold(1.0)
    start, time = in_gripper(cell, 'held'), cell.time
    arm.hold(60.0)
    creep = np.linalg.norm(in_gripper(cell, 'held') - start) / (cell.time - time)
    print('creep at %g N: %.3f um/s' % (force, creep * 1e6))
    assert creep < CREEP_LIMIT
    assert cell.finger().motion == ON_OBJECT


def test_a_held_kilogram_stays_in_the_grasp_while_the_arm_moves_at_full_speed(make_cell, between_pads):
    """Every joint at its velocity limit (the slowest sets the time), there and back, holding 1 kg."""
    cell = make_cell(between_pads(0.05, mass=1.0), START)
    arm = Arm(cell)
    assert close_on(cell, 125.0).motion == ON_OBJECT
    arm.move_tool([0.0, 0.0, 0.15], 1.5)
    arm.hold(0.5)
    start = in_gripper(cell, 'held')
    delta = np.array([1.5, 0.4, -0.6, 1.0, 0.0, 3.0])
    # A quintic's peak velocity is 1.875 times its mean: the fastest joint reaches its limit.
    duration = float(np.max(1.875 * np.abs(delta) / cell.arm_velocity_limits))
    worst, peak = 0.0, np.zeros(6)
    for sign in (1.0, -1.0):
        for _ in arm.move_joints(sign * delta, duration):
            worst = max(worst, float(np.linalg.norm(in_gripper(cell, 'held') - start)))
            peak = np.maximum(peak, np.abs(cell.arm_velocity))
    arm.hold(0.5)
    slip = float(np.linalg.norm(in_gripper(cell, 'held') - start))
    print('full speed: peak joint speeds %s of the limits; slip %.2f mm (worst %.2f mm)'
          % (np.round(peak / cell.arm_velocity_limits, 2).tolist(), slip * 1e3, worst * 1e3))
    assert cell.protective_stop is None
    assert np.max(peak / cell.arm_velocity_limits) > 0.95
    assert cell.finger().motion == ON_OBJECT
    assert slip < 0.005, 'the object slipped %.1f mm in the grasp' % (slip * 1e3)
