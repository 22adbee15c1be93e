"""The simulated cell's clock (devices/sim_clock.py): whole periods, paced to the wall clock at a factor."""
import pytest

from ur3_ft_gripper_description.devices import sim_params
from ur3_ft_gripper_description.devices.sim_clock import SimClock, check_factor, clock_stride, wall_cycles


class Wall(object):
    """A wall clock the test moves by hand."""

    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_control_periods_are_whole_nanoseconds_and_time_never_drifts():
    for hz, period_ns in ((125, 8000000), (500, 2000000)):
        clock = SimClock(hz)
        assert clock.period_ns == period_ns
        for _ in range(125000):  # 1000 s of a CB3, 250 s of an e-Series
            clock.tick()
        assert clock.nanoseconds == 125000 * period_ns
        assert clock.time == pytest.approx(125000 * period_ns * 1e-9, abs=1e-12)


def test_at_factor_one_a_simulated_second_takes_a_wall_clock_second():
    wall = Wall()
    clock = SimClock(125, 1.0, wall=wall)
    clock.start()
    waited = 0.0
    for _ in range(125):
        clock.tick()
        wall.now += 0.001  # the cycle's work
        pause = clock.pause()
        waited += pause
        wall.now += pause
    assert clock.time == pytest.approx(1.0)
    assert wall.now - 100.0 == pytest.approx(1.0)
    assert waited == pytest.approx(1.0 - 125 * 0.001)


def test_at_factor_two_the_waits_halve_and_at_zero_there_are_none():
    wall = Wall()
    clock = SimClock(500, 2.0, wall=wall)
    clock.start()
    clock.tick()
    assert clock.pause() == pytest.approx(0.001)
    fast = SimClock(500, 0.0, wall=wall)
    fast.start()
    fast.tick()
    assert fast.pause() == 0.0


def test_a_late_cycle_is_neither_stretched_nor_made_up_for_with_a_burst():
    wall = Wall()
    clock = SimClock(125, 1.0, wall=wall)
    clock.start()
    clock.tick()
    wall.now += 0.020  # a cycle that took 20 ms of an 8 ms period: late, not yet a stall
    assert clock.time == pytest.approx(0.008)  # simulated time moved one period, no more
    assert clock.pause() == 0.0
    clock.tick()
    wall.now += 1.0  # a stall (a suspended machine): the pace starts anew from here
    assert clock.pause() == 0.0
    clock.tick()
    assert clock.pause() == pytest.approx(0.008)


@pytest.mark.parametrize('hz, factor', [(0, 1.0), (-125, 1.0), (125, -1.0), (125, float('nan'))])
def test_a_clock_it_cannot_keep_is_refused_in_one_line(hz, factor):
    with pytest.raises(ValueError) as error:
        SimClock(hz, factor)
    assert '\n' not in str(error.value)


def test_a_factor_other_than_one_needs_the_simulated_clock():
    assert check_factor(True, 0.0) == 0.0
    assert check_factor(False, 1.0) == 1.0
    with pytest.raises(sim_params.ParamError) as error:
        check_factor(False, 0.0)
    assert 'use_sim_time:=true' in str(error.value)


@pytest.mark.parametrize('periods', [0.0, 0.3, 1.0, 1.49, 1.51, 2.0, 3.7, 9.9, 10.0, 55.0])
def test_on_the_wall_clock_a_late_cycle_is_made_up_in_periods_of_the_robot(periods):
    period, longest = 0.008, 0.08
    cycles = wall_cycles(periods * period, period, longest)
    assert sum(cycles) == pytest.approx(min(periods * period, longest))  # the time the host let pass, capped
    assert all(c == period for c in cycles[:-1]) and 0.0 <= cycles[-1] <= 1.5 * period


@pytest.mark.parametrize('loop_hz, frequency, stride, clock_hz', [
    (500, 0.0, 1, 500.0),    # the default: every control cycle
    (500, 100.0, 5, 100.0),  # an e-Series at Gazebo's usual 100 Hz: ROS time in 10 ms steps
    (500, 120.0, 4, 125.0),  # never below the rate asked: 125 Hz, not 100
    (125, 100.0, 1, 125.0),  # a CB3's 8 ms periods already meet it
    (500, 1000.0, 1, 500.0),  # above the control rate: every cycle, no faster
])
def test_clock_goes_out_every_whole_stride_of_cycles_never_below_the_rate_asked(loop_hz, frequency, stride,
                                                                                   clock_hz):
    assert clock_stride(True, loop_hz, frequency, 100.0) == stride
    clock = SimClock(loop_hz, 0.0, stride=stride)
    published = []
    for _ in range(loop_hz):  # one simulated second
        clock.tick()
        if clock.published:
            published.append(clock.nanoseconds)
    assert len(published) == clock_hz
    assert {b - a for a, b in zip(published, published[1:])} == {round(1e9 / clock_hz)}
    assert published[-1] == 1000000000  # the second's last cycle is on /clock


@pytest.mark.parametrize('use_sim_time, frequency, named', [
    (True, 50.0, 'at least 100 Hz'),   # the FT 300's 100 Hz would come two samples at a time
    (False, 100.0, 'use_sim_time:=true'),
])
def test_a_clock_rate_that_would_batch_a_stream_or_has_no_clock_is_refused_in_one_line(use_sim_time, frequency,
                                                                                      named):
    with pytest.raises(sim_params.ParamError) as error:
        clock_stride(use_sim_time, 500, frequency, 100.0)
    assert '~pub_clock_frequency=%g' % frequency in str(error.value) and named in str(error.value)
    assert '\n' not in str(error.value)
