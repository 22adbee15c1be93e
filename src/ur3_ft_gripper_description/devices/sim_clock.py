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

import time

from . import sim_params

PARAMETERS = (
    sim_params.Param('~real_time_factor', 1.0, 'With use_sim_time (the node publishes /clock): simulated seconds '
                     'per wall-clock second the cell is paced to; 0: as fast as the machine allows. Without '
                     'use_sim_time only 1 (the wall clock) is possible', sim_params.number(minimum=0.0)),
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

    def __init__(self, hz, factor=1.0, wall=time.monotonic, resync_after=RESYNC_AFTER):
        if not hz > 0:
            raise ValueError('a clock of %r Hz: the rate must be above 0' % (hz,))
        if not factor >= 0:
            raise ValueError('a real-time factor of %r: use 0 (as fast as possible) or more' % (factor,))
        # Whole nanoseconds, as /clock carries them: 125 Hz and 500 Hz give 8 ms and 2 ms exactly.
        self.period_ns = int(round(1e9 / hz))
        self.factor = float(factor)
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
