"""The physics cell's real-time factor (physics/pacing.py): what the arm's node reports on /diagnostics."""
from ur3_ft_gripper_description.devices.physics.pacing import RealTimeMeter


def feed(meter, factor, seconds, start=0.0, period=0.008):
    wall = start
    for k in range(int(round(seconds / period)) + 1):
        wall = start + k * period
        meter.add(wall, wall * factor)
    return wall


def test_the_factor_is_simulated_over_wall_clock_seconds_across_the_window():
    meter = RealTimeMeter(window=3.0, slow=0.9)
    assert meter.factor() is None
    feed(meter, 1.0, 5.0)
    assert abs(meter.factor() - 1.0) < 1e-9 and meter.full()
    assert meter.slow_warning() is None


def test_a_slow_machine_is_warned_once_in_one_line_after_a_whole_window():
    meter = RealTimeMeter(window=3.0, slow=0.9)
    feed(meter, 0.5, 2.0)
    assert meter.slow_warning() is None  # not a whole window yet
    end = feed(meter, 0.5, 2.0, start=2.008)
    warning = meter.slow_warning()
    assert warning and '\n' not in warning and '0.50 x real time' in warning and 'physics:=false' in warning
    feed(meter, 0.5, 5.0, start=end + 0.008)
    assert meter.slow_warning() is None  # once


def test_a_cell_paced_as_fast_as_possible_is_never_slow():
    meter = RealTimeMeter(window=3.0, slow=0.0, paced_to=0.0)
    feed(meter, 0.2, 5.0)
    assert meter.slow_warning() is None


def test_a_cell_paced_at_a_factor_is_slow_below_that_factor():
    meter = RealTimeMeter(window=3.0, slow=0.9 * 4.0, paced_to=4.0)
    feed(meter, 3.0, 5.0)
    warning = meter.slow_warning()
    assert warning and '3.00 x real time' in warning and 'the 4 asked for' in warning
