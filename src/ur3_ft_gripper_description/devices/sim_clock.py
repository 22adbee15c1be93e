"""The simulated cell's one clock, without ROS: whole control periods, paced to the wall clock at a factor.

With ``use_sim_time`` the simulated arm's node (``ur_hardware_interface``)
is the cell's clock, as Gazebo is in its simulations: every control cycle
advances simulated time by exactly one period (8 ms on a CB3, 2 ms on an
e-Series: ``loop_hz`` of ur_robot_driver's controller configuration), the
node publishes it on ``/clock``, and every node of the cell runs on it
(``rospy.Time``, ``rospy.Rate``, actionlib, tf).

No period is ever stretched or skipped to keep up with the wall clock. The
factor only decides how long the loop waits between cycles: at 1.0 a
simulated second takes a wall-clock second, at 0 there is no wait (as fast
as the machine allows). A machine too busy to keep the pace makes the whole
cell slower, and changes nothing of what happens in it.
"""

import math
import time

from . import sim_params

PARAMETERS = (
    sim_params.Param('~real_time_factor', 1.0, 'With use_sim_time (the node publishes /clock): simulated seconds '
                     'per wall-clock second the cell is paced to; 0: as fast as the machine allows. Without '
                     'use_sim_time only 1 (the wall clock) is possible', sim_params.number(minimum=0.0)),
    sim_params.Param('~pub_clock_frequency', 0.0, 'With use_sim_time: the least rate of /clock (Hz of simulated '
                     "time), as Gazebo's pub_clock_frequency. /clock then goes out every N control cycles, N the "
                     'most that keep it at or above this rate, so every node\'s ROS time moves in steps of at '
                     'most 1/rate; the arm\'s streams keep their rates and stamps. 0: every control cycle (2 ms '
                     'on an e-Series). At least the FT 300\'s rate (100 Hz), which samples on ROS time. Every '
                     'node reads every /clock message: fewer make a cell faster than real time run faster',
                     sim_params.number(minimum=0.0)),
)

# A loop later than this (wall-clock s) behind its pace starts the pace anew from where it is, instead of
# running cycles back to back to make up for a stall (a suspended machine, a debugger's breakpoint).
RESYNC_AFTER = 0.25
# Without use_sim_time, a cycle that comes this many periods after the last one is late (wall_cycles).
LATE_AFTER_PERIODS = 1.5


class SimClock(object):
    """Simulated time in whole periods of 1/`hz` s, and the wall-clock waits that pace it at `factor`.

    The loop: ``start()`` once, then per cycle ``tick()`` (the new simulated
    time), the cycle's work, and a wait of ``pause()`` wall-clock seconds.
    """

    def __init__(self, hz, factor=1.0, wall=time.monotonic, resync_after=RESYNC_AFTER, stride=1):
        if not hz > 0:
            raise ValueError('a clock of %r Hz: the rate must be above 0' % (hz,))
        if not factor >= 0:
            raise ValueError('a real-time factor of %r: use 0 (as fast as possible) or more' % (factor,))
        # Whole nanoseconds, as /clock carries them: 125 Hz and 500 Hz give 8 ms and 2 ms exactly.
        self.period_ns = int(round(1e9 / hz))
        self.factor = float(factor)
        self.stride = int(stride)  # control cycles per /clock message (clock_stride)
        self.cycles = 0
        self._wall = wall
        self._resync_after = float(resync_after)
        self._anchor = None  # (wall-clock time, cycles then) the pace counts from

    @property
    def period(self):
        """The control period (s)."""
        return self.period_ns * 1e-9

    @property
    def nanoseconds(self):
        """Simulated time (ns), a whole number of periods."""
        return self.cycles * self.period_ns

    @property
    def time(self):
        """Simulated time (s)."""
        return self.nanoseconds * 1e-9

    @property
    def published(self):
        """The cycle just ticked ends a stride: /clock carries its time."""
        return self.cycles % self.stride == 0

    def start(self):
        """The pace counts from now."""
        self._anchor = (self._wall(), self.cycles)

    def tick(self):
        """Advance one period; the new simulated time (s)."""
        self.cycles += 1
        return self.time

    def pause(self):
        """Wall-clock seconds to wait before the next cycle: 0 when running as fast as possible or late."""
        if self.factor == 0.0:
            return 0.0
        now = self._wall()
        if self._anchor is None:
            self._anchor = (now, self.cycles)
        wall, cycles = self._anchor
        due = wall + (self.cycles - cycles) * self.period / self.factor
        if now - due > self._resync_after:
            self._anchor = (now, self.cycles)
            return 0.0
        return max(due - now, 0.0)


def check_factor(use_sim_time, factor):
    """The real-time factor if it can be kept; ParamError naming the fix otherwise."""
    if not use_sim_time and factor != 1.0:
        raise sim_params.ParamError('~real_time_factor=%g needs use_sim_time:=true: on the wall clock the cell '
                                    'runs at real time (1)' % factor)
    return factor


def clock_stride(use_sim_time, loop_hz, frequency, least_hz):
    """Control cycles per /clock message for ~pub_clock_frequency `frequency` (0: every cycle); ParamError
    naming the fix when it cannot be kept. `least_hz` is the fastest rate another node of the cell samples at on
    ROS time: a clock in coarser steps would make it serve several samples at once."""
    if frequency == 0.0:
        return 1
    if not use_sim_time:
        raise sim_params.ParamError('~pub_clock_frequency=%g needs use_sim_time:=true: on the wall clock the node '
                                    'publishes no /clock' % frequency)
    if frequency < least_hz:
        raise sim_params.ParamError('~pub_clock_frequency=%g: use 0 (every control cycle) or at least %g Hz, the '
                                    'FT 300\'s rate, which samples on ROS time' % (frequency, least_hz))
    return max(1, int(math.floor(loop_hz / frequency + 1e-9)))


def wall_cycles(elapsed, period, longest):
    """The control cycles (s each) that run `elapsed` wall-clock seconds, at most `longest`, without use_sim_time.

    The robot's controller never runs a cycle longer than its period, whatever the host does. One long
    cycle after a stall of this host would let a trajectory run ahead of the joints by its whole length,
    and a path tolerance would read the stall as the arm falling behind. So a late cycle is made up in
    periods, and only the last one takes the remainder (under one and a half periods).
    """
    late = min(max(elapsed, 0.0), longest)
    cycles = []
    while late > LATE_AFTER_PERIODS * period:
        cycles.append(period)
        late -= period
    cycles.append(late)
    return cycles
