"""How well the physics cell keeps the pace it is given (no ROS).

The arm's node steps the cell at its control rate, either on its own
simulated clock paced to the wall clock at a real-time factor
(devices/sim_clock.py; 0: as fast as possible), or, without use_sim_time, by
the wall-clock time since the last cycle. When the machine cannot step the
cell as fast as asked, the real-time factor achieved (simulated seconds per
wall-clock second) falls below the pace. The node publishes it on
/diagnostics and warns once.
"""

import collections

# The factor is measured over this many wall-clock seconds.
WINDOW = 3.0
# Below this over a whole window, the machine does not keep up (warned once).
SLOW = 0.9


class RealTimeMeter(object):
    """The real-time factor over the last `window` seconds of (wall-clock time, simulated time) samples."""

    def __init__(self, window=WINDOW, slow=SLOW, paced_to=1.0):
        """`paced_to`: the factor the loop is paced to; None or 1: real time, 0: as fast as possible (never slow)."""
        self.window, self.slow = float(window), float(slow)
        self.paced_to = 1.0 if paced_to is None else float(paced_to)
        self._samples = collections.deque()
        self._warned = False

    def add(self, wall, simulated):
        """One sample: the wall-clock time and the cell's time then (s, any origins)."""
        samples = self._samples
        samples.append((float(wall), float(simulated)))
        while len(samples) > 2 and samples[-1][0] - samples[1][0] >= self.window:
            samples.popleft()

    def factor(self):
        """Simulated over wall-clock seconds across the window; None before there are two samples."""
        if len(self._samples) < 2:
            return None
        (wall0, sim0), (wall1, sim1) = self._samples[0], self._samples[-1]
        return (sim1 - sim0) / (wall1 - wall0) if wall1 > wall0 else None

    def full(self):
        """The samples span a whole window."""
        return len(self._samples) >= 2 and self._samples[-1][0] - self._samples[0][0] >= self.window

    def slow_warning(self):
        """The one line to warn with, the first time a whole window ran slower than `slow`; else None."""
        factor = self.factor()
        if self._warned or self.paced_to == 0.0 or not self.full() or factor is None or factor >= self.slow:
            return None
        self._warned = True
        return ('the physics cell runs at %.2f x real time over the last %g s (below %g of the %g asked for): this '
                'machine cannot step it that fast, so the simulated cell runs slower; close other programs, or '
                'use the kinematic simulation (physics:=false)' % (factor, self.window, self.slow, self.paced_to))
