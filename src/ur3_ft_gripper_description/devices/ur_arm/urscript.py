"""The part of URScript that script_command users send, without ROS.

ur_robot_driver forwards what arrives on script_command to the robot; the
robot runs it as a program (`def name(): ... end`, or bare statements) that
replaces the running one, or as a secondary program (`sec name(): ... end`)
that runs beside it and may not move the arm. The simulation understands:
movej(q, a=1.4, v=1.05, t=0, r=0) with joint positions (a pose `p[...]`
needs inverse kinematics, which the node supplies), set_standard_digital_out,
set_configurable_digital_out, set_tool_digital_out, set_digital_out,
set_standard_analog_out, set_analog_out, set_tool_voltage, textmsg, popup,
sleep and sync. Anything else is refused whole with one line, as the robot
refuses a program that does not compile. Default speeds are those of the
URScript manual's movej.
"""

import ast
import math
import re

import numpy as np

MOVEJ_DEFAULTS = {'a': 1.4, 'v': 1.05, 't': 0.0, 'r': 0.0}


class ScriptError(ValueError):
    """A script the simulated robot cannot run (as a compile error on the robot)."""


class Statement(object):
    def __init__(self, name, args, kwargs):
        self.name = name
        self.args = args
        self.kwargs = kwargs

    def __repr__(self):
        return 'Statement(%r, %r, %r)' % (self.name, self.args, self.kwargs)


class Pose(list):
    """A URScript pose p[x, y, z, rx, ry, rz] (m, rotation vector in rad)."""


KNOWN = ('movej', 'set_standard_digital_out', 'set_configurable_digital_out', 'set_tool_digital_out',
         'set_digital_out', 'set_standard_analog_out', 'set_analog_out', 'set_tool_voltage', 'textmsg',
         'popup', 'sleep', 'sync')


def _value(node):
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == '_pose':
        return Pose(ast.literal_eval(node.args[0]))
    return ast.literal_eval(node)


def parse(script):
    """(secondary, [Statement]) of a script; raises ScriptError naming the line."""
    lines = [line.strip() for line in script.strip().splitlines()]
    lines = [line for line in lines if line and not line.startswith('#')]
    if not lines:
        raise ScriptError('empty script')
    secondary = False
    header = re.match(r'^(def|sec)\s+\w+\s*\(\s*\)\s*:$', lines[0])
    if header:
        if lines[-1] != 'end':
            raise ScriptError("the program '%s' has no closing 'end'" % lines[0])
        secondary = header.group(1) == 'sec'
        lines = lines[1:-1]
    statements = []
    for line in lines:
        text = re.sub(r'\bp\[([^\]]*)\]', r'_pose([\1])', line)
        try:
            call = ast.parse(text, mode='eval').body
            if not isinstance(call, ast.Call) or not isinstance(call.func, ast.Name):
                raise ValueError('not a function call')
            name = call.func.id
            if name not in KNOWN:
                raise ValueError('%s() is not simulated (simulated: %s)' % (name, ', '.join(KNOWN)))
            args = [_value(a) for a in call.args]
            kwargs = {k.arg: _value(k.value) for k in call.keywords}
        except (SyntaxError, ValueError) as exc:
            raise ScriptError('%r: %s' % (line, exc))
        if secondary and name in ('movej', 'sleep'):
            raise ScriptError('%r: a secondary program (sec) cannot move the arm or wait' % line)
        statement = Statement(name, args, kwargs)
        # Checked here, as the robot's compiler does, so that a bad argument stops no running program.
        try:
            CHECKS.get(name, lambda s: None)(statement)
        except (TypeError, ValueError) as exc:
            raise ScriptError('%r: %s' % (line, exc))
        statements.append(statement)
    return secondary, statements


def movej_arguments(statement):
    """(target, a, v, t) of a movej Statement; target is a joint list or a Pose."""
    names = ['q', 'a', 'v', 't', 'r']
    values = dict(MOVEJ_DEFAULTS)
    for name, value in zip(names, statement.args):
        values[name] = value
    for name, value in statement.kwargs.items():
        if name not in names:
            raise ScriptError('movej() has no argument %s' % name)
        values[name] = value
    target = values.get('q')
    if target is None or len(target) != 6:
        raise ScriptError('movej() needs six joint positions or a pose p[x, y, z, rx, ry, rz]')
    numbers = [float(x) for x in target] + [float(values[k]) for k in ('a', 'v', 't')]
    if not all(math.isfinite(x) for x in numbers) or values['a'] <= 0 or values['v'] <= 0 or values['t'] < 0:
        raise ScriptError('movej(): positions finite, a > 0, v > 0, t >= 0')
    return target, float(values['a']), float(values['v']), float(values['t'])


def sleep_seconds(statement):
    """The seconds of a sleep(t) Statement."""
    values = list(statement.args) + [statement.kwargs[k] for k in ('t',) if k in statement.kwargs]
    if len(values) != 1 or set(statement.kwargs) - {'t'}:
        raise ScriptError('sleep() takes one argument, the time in seconds')
    try:
        seconds = float(values[0])
    except (TypeError, ValueError):
        seconds = float('nan')
    if not math.isfinite(seconds) or seconds < 0.0:
        raise ScriptError('sleep(t): t must be a finite number of seconds >= 0')
    return seconds


def _check_digital_out(statement):
    if len(statement.args) != 2 or not isinstance(statement.args[0], int):
        raise ScriptError('%s(n, b) takes an output number and a boolean' % statement.name)


def _check_analog_out(statement):
    if len(statement.args) != 2 or not isinstance(statement.args[0], int) or \
            not isinstance(statement.args[1], (int, float)):
        raise ScriptError('%s(n, f) takes an output number and a fraction of its range' % statement.name)


def _check_tool_voltage(statement):
    if len(statement.args) != 1 or not isinstance(statement.args[0], int):
        raise ScriptError('set_tool_voltage(voltage) takes 0, 12 or 24')


CHECKS = {'movej': movej_arguments, 'sleep': sleep_seconds,
          'set_standard_digital_out': _check_digital_out, 'set_digital_out': _check_digital_out,
          'set_configurable_digital_out': _check_digital_out, 'set_tool_digital_out': _check_digital_out,
          'set_standard_analog_out': _check_analog_out, 'set_analog_out': _check_analog_out,
          'set_tool_voltage': _check_tool_voltage}


class Wait(object):
    """sleep(t): the program waits t seconds; the arm holds."""

    def __init__(self, seconds):
        self.total_time = float(seconds)


class JointMove(object):
    """movej: all joints start and stop together; the leading joint has a trapezoidal speed profile."""

    def __init__(self, start, target, acceleration, velocity, duration, velocity_limits):
        self.start = np.asarray(start, dtype=float)
        self.delta = np.asarray(target, dtype=float) - self.start
        distance = float(np.max(np.abs(self.delta)))
        # No joint may exceed its limit: the leading joint's speed is capped by the slowest ratio.
        ratios = np.abs(self.delta) / max(distance, 1e-12)
        cap = min(float(v) / r for v, r in zip(velocity_limits, ratios) if r > 1e-9) if distance > 0 else velocity
        velocity = min(velocity, cap)
        if distance <= 0.0:
            self.duration, self.v, self.a, self.distance, self.stretch = 0.0, velocity, acceleration, 0.0, 1.0
            return
        if distance >= velocity ** 2 / acceleration:
            natural = distance / velocity + velocity / acceleration
        else:
            velocity = math.sqrt(distance * acceleration)
            natural = 2.0 * distance / velocity
        # movej's t: the same profile, stretched to the requested time.
        self.stretch = natural / duration if duration > natural else 1.0
        self.duration, self.v, self.a, self.distance = natural, velocity, acceleration, distance

    @property
    def total_time(self):
        return self.duration / self.stretch

    def fraction(self, t):
        """Share of the way covered after t seconds (0..1)."""
        t = t * self.stretch
        if self.distance <= 0.0 or t >= self.duration:
            return 1.0
        if t <= 0.0:
            return 0.0
        ramp = self.v / self.a
        if 2 * ramp >= self.duration:  # triangular
            half = self.duration / 2.0
            peak = self.distance / half
            s = 0.5 * peak / half * t ** 2 if t <= half else \
                self.distance - 0.5 * peak / half * (self.duration - t) ** 2
        elif t < ramp:
            s = 0.5 * self.a * t ** 2
        elif t > self.duration - ramp:
            s = self.distance - 0.5 * self.a * (self.duration - t) ** 2
        else:
            s = 0.5 * self.a * ramp ** 2 + self.v * (t - ramp)
        return min(1.0, max(0.0, s / self.distance))

    def position(self, t):
        return self.start + self.delta * self.fraction(t)
