"""The 2F-140's register machine (gripper_sim.RegisterGripper) on the physics cell's fingers, through the link.

The cell steps in a thread as the arm's node steps it; the register machine runs as the gripper's
node runs it, over PhysicsFingers and a real CellClient. Known truths: the object's width and the
fingers' speed through the register scales of config/sim_devices.yaml, and the status codes of the
manual (section 4.4).
"""
import time

import numpy as np
import pytest

from ur3_ft_gripper_description.devices import gripper_sim
from ur3_ft_gripper_description.devices.physics.link import CellClient
from ur3_ft_gripper_testing.grasp import gpo_tolerance
from ur3_ft_gripper_testing.physics import START, Served

PERIOD = 0.02  # the gripper node's 50 Hz


@pytest.fixture
def registers(make_cell, between_pads, tmp_path):
    """registers(world text) -> a RegisterGripper on that cell's fingers."""
    made = []

    def make(world, sample_period=None):
        served = Served(make_cell(world, START), str(tmp_path / ('cell%d.sock' % len(made))))
        made.append(served)
        spec = gripper_sim.spec_from_params(lambda name, default=None: default)
        fingers = gripper_sim.PhysicsFingers(CellClient(served.server.path), spec, sample_period=sample_period)
        return gripper_sim.RegisterGripper(spec, lambda text: None, fingers=fingers)
    yield make
    for served in made:
        served.close()


def command(gripper, **registers):
    values = dict.fromkeys(gripper_sim.COMMAND_FIELDS, 0)
    values.update(registers)
    gripper.set_command(values)


def run_until(gripper, condition, seconds=10.0):
    """Advance at the node's rate until condition(status); the status."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        gripper.advance(PERIOD)
        status = gripper.status()
        if condition(status):
            return status
        time.sleep(PERIOD)
    raise AssertionError('not within %g s: %s' % (seconds, gripper.status()))


def activate(gripper):
    command(gripper, rACT=1, rGTO=1, rPR=0, rSP=255, rFR=150)
    return run_until(gripper, lambda s: s['gSTA'] == 3 and s['gOBJ'] == 3)


def test_closing_on_an_object_reads_gobj_2_at_its_width_and_opening_reads_3(registers, between_pads):
    gripper = registers(between_pads(0.05, mass=0.3))
    opened = activate(gripper)
    assert opened['gPO'] == 3  # the model's open end reads as the request: fully open
    command(gripper, rACT=1, rGTO=1, rPR=255, rSP=128, rFR=150)
    assert run_until(gripper, lambda s: s['gOBJ'] != 3)['gOBJ'] == 0  # moving
    held = run_until(gripper, lambda s: s['gOBJ'] != 0)
    scale = gripper.spec.scale
    assert held['gOBJ'] == 2 and abs(held['gPO'] - scale.position(0.05)) <= gpo_tolerance(scale), held
    assert held['gCU'] == pytest.approx(gripper.spec.max_grip_current * (10 + 115 * 150 / 255.0) / 125.0, abs=2)
    command(gripper, rACT=1, rGTO=1, rPR=0, rSP=255, rFR=150)
    assert run_until(gripper, lambda s: s['gOBJ'] != 0 and s['gPR'] == 0) == dict(
        gACT=1, gGTO=1, gSTA=3, gOBJ=3, gFLT=0, gPR=0, gPO=3, gCU=0)


def test_closing_on_nothing_ends_at_the_request(registers):
    gripper = registers('')
    activate(gripper)
    command(gripper, rACT=1, rGTO=1, rPR=255, rSP=255, rFR=50)
    closed = run_until(gripper, lambda s: s['gOBJ'] != 0 and s['gPR'] == 255)
    assert (closed['gOBJ'], closed['gPO']) == (3, int(gripper.spec.gpo_closed))
    command(gripper, rACT=1, rGTO=1, rPR=100, rSP=255, rFR=50)
    assert run_until(gripper, lambda s: s['gOBJ'] != 0 and s['gPR'] == 100)['gPO'] == 100


def test_stopping_holds_the_fingers_where_they_are(registers):
    gripper = registers('')
    activate(gripper)
    command(gripper, rACT=1, rGTO=1, rPR=255, rSP=0, rFR=50)
    run_until(gripper, lambda s: s['gPO'] > 60)
    command(gripper, rACT=1, rGTO=0, rPR=255, rSP=0, rFR=50)
    stopped = run_until(gripper, lambda s: s['gGTO'] == 0)
    time.sleep(0.5)
    gripper.advance(0.5)
    assert gripper.status()['gPO'] == stopped['gPO'] and stopped['gPO'] < 230


def stroke_samples(gripper, seconds=60.0):
    """Advance at the node's rate until the fingers stop; [(cell time, pad gap)] read from the cell
    between the advances, as often as the link answers (at 50 Hz a fast stroke's middle is a few samples)."""
    client = gripper.fingers.client
    samples = {}
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        gripper.advance(PERIOD)
        if gripper.status()['gOBJ'] != 0:
            return sorted(samples.items())
        tick = time.monotonic() + PERIOD
        while time.monotonic() < tick:
            stamp, state = client.finger()
            samples[stamp] = state['opening']
            time.sleep(0.001)
    raise AssertionError('the fingers still move after %g s: %s' % (seconds, gripper.status()))


def gap_rate(gripper, samples):
    """The gap's rate of change (m/s, opening > 0) over the middle half of the model's stroke, fitted to the
    samples there: away from the ends, where the fingers speed up and slow down."""
    model = gripper.fingers.client.info['gripper']
    low, high = model['min_opening'], model['max_opening']
    middle = [(t, gap) for t, gap in samples if low + 0.25 * (high - low) <= gap <= low + 0.75 * (high - low)]
    assert len(middle) >= 10, 'too few samples in the middle of the stroke: %s' % samples
    times, gaps = zip(*middle)
    return np.polyfit(times, gaps, 1)[0]


@pytest.mark.parametrize('rsp', [0, 128, 255])
def test_the_fingers_close_and_open_at_the_speed_rsp_asks(registers, rsp):
    gripper = registers('')
    spec = gripper.spec
    # The register scale: min_speed at rSP 0 to max_speed at 255, linear (config/sim_devices.yaml).
    asked = spec.min_speed + (spec.max_speed - spec.min_speed) * rsp / 255.0
    activate(gripper)
    command(gripper, rACT=1, rGTO=1, rPR=255, rSP=rsp, rFR=50)
    closing = -gap_rate(gripper, stroke_samples(gripper))
    command(gripper, rACT=1, rGTO=1, rPR=0, rSP=rsp, rFR=50)
    opening = gap_rate(gripper, stroke_samples(gripper))
    # Mid-stroke the finger servo follows its ramp at the ramp's own speed (within 0.01 % on MuJoCo
    # 3.2.3 and 4); 2 % is slack for the solver, far finer than the step between these rSP values.
    assert closing == pytest.approx(asked, rel=0.02)
    assert opening == pytest.approx(asked, rel=0.02)


def test_a_node_running_late_publishes_each_status_with_the_fingers_of_its_own_time(registers):
    """On a simulated clock the node serves the ticks it missed, late: here the whole stroke at rSP 0. Each
    status must still show the fingers at its tick (the cell keeps them), so that the statuses, one per
    50th of a simulated second, move at the speed rSP asks and end closed, not all at the late moment."""
    gripper = registers('', sample_period=PERIOD)
    spec, client = gripper.spec, gripper.fingers.client
    activate(gripper)
    command(gripper, rACT=1, rGTO=1, rPR=255, rSP=0, rFR=50)
    commanded = client.finger()[0]
    end = time.monotonic() + 60.0
    while client.finger()[1]['motion'] == 'moving' and time.monotonic() < end:
        time.sleep(0.05)  # the node starved meanwhile
    # The fingers stopped between two ticks, or at the last: the ticks run on to the first after it.
    last = int(client.finger()[0] / PERIOD) + 1
    while client.finger()[0] < last * PERIOD and time.monotonic() < end:
        time.sleep(0.005)
    ticks = [n * PERIOD for n in range(int(commanded / PERIOD) + 1, last + 1)]
    statuses = []
    for at in ticks:
        gripper.advance(PERIOD, at)
        statuses.append(gripper.status())
    assert (statuses[-1]['gOBJ'], statuses[-1]['gPO']) == (3, int(spec.gpo_closed))
    closing = -gap_rate(gripper, [(at, spec.scale.opening(s['gPO'])) for at, s in zip(ticks, statuses)
                                  if s['gOBJ'] == 0])
    assert closing == pytest.approx(spec.min_speed, rel=0.02)
