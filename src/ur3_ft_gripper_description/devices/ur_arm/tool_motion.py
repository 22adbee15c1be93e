"""URScript's motion commands as motion generators, without ROS.

The simulated controller runs one motion at a time: every control cycle
(8 ms CB3, 2 ms e-Series) it calls `motion.step(dt, q, qd)` and commands the
joint positions it returns (joints.MOVE: where the joints are to be at the end
of the cycle; joints.SERVO for Servo). A motion generates from its own
commanded state, not from the measured joints (which lag the command a little
on the physics cell): q and qd are read once, when the motion starts.

- `motion.returned`: the URScript call returns now: at the end of the move, on
  entering the blend radius, after speedl/speedj's `t`, after servoj's `t`.
- `motion.done`: the motion has ended; the arm holds after. A speedl or
  speedj never ends by itself: the script ends it with the next motion
  (stopl, stopj, a move) or, at the program's end, the caller with a stop.
- A motion the arm cannot make raises MotionError (one line): at construction
  where it is known before moving (a target out of reach, beyond the joint
  limits), else from step() (the path leaves the reach, a joint would pass
  its limit or its speed limit near a singularity). The real robot makes a
  protective stop there.

The commands, with the URScript manual's signatures and defaults (Universal
Robots, "The URScript Programming Language", Module motion; e-Series 5.x and
CB3 3.x alike unless said):
- JointMove, movej(q, a=1.4, v=1.05, t=0, r=0): a trapezoid on the leading
  joint, the others scaled to arrive together; `t` takes priority over a and v
  ("Time setting has priority over speed and acceleration settings"): the same
  profile stretched or squeezed to last t, never beyond a joint's speed limit.
- LinearMove, movel(pose, a=1.2, v=0.25, t=0, r=0): the TCP on a straight line,
  its orientation slerped in step, a trapezoid on the tool's linear speed. The
  manual gives a and v in m/s^2 and m/s only; for the rotation the controller
  uses 4 rad/s per m/s and 4 rad/s^2 per m/s^2, profiles both and lets the
  longer set the time (Universal Robots forum, "MoveL: Tool Angular Speed"),
  so a pure rotation moves at 4 v rad/s.
- ProcessMove, movep(pose, a=1.2, v=0.25, r=0): the same line and profile;
  blended from another movep the corner is a circular arc at the tool speed
  the move had on entering the blend radius (the manual: "Blend circular (in
  tool-space) and move linear (in tool-space)", constant tool speed v).
- ToolSpeed, speedl(xd, a, t, aRot='a') and ToolStop, stopl(a, aRot='a'): the
  tool twist (base frame: m/s, then rotation-vector rate rad/s) ramps linearly
  to xd (to zero), its linear part at a, its angular at aRot (default: a's
  value in rad/s^2); both parts arrive together. The joints follow by inverse
  kinematics of the integrated pose, the twist scaled down uniformly where a
  joint would pass its speed limit. speedl's t: the manual (5.x, and 3.x from
  3.3 on) returns after t if given, "regardless of the target speed has been
  reached", else when the target speed is reached; older software (CB2 1.x,
  CB3 before 3.3) named it t_min, "minimal time before function returns":
  `minimum_time=True` returns only when both t passed and the speed is reached.
- JointSpeed, speedj(qd, a, t) and JointStop, stopj(a): the same in joint
  space, a the leading joint's acceleration. stopj and stopl have no default a
  in the manual, so a is required here too.
- Servo, servoj(q, a, v, t=0.002, lookahead_time=0.1, gain=300): the manual says
  a and v are not used; the joints follow q as a first-order lag with the
  lookahead time as time constant (as joints.KinematicJoints follows SERVO),
  within their speed limits; gain is not modelled; it returns after t.

Blends (r > 0): a move returns once its TCP is within r of its target, and the
next move, built with `previous=` the running one, superposes the rest of the
first and the beginning of its own from the first's target: the commanded
state is the first move's plus the second's displacement from its start (for
two Cartesian moves position plus position and rotation after rotation, else
joint plus joint). The second starts when the first has just its own
acceleration time left, so with equal a and v the two ramps mirror each other:
the tool's speed stays within v, continuous, and the path leaves the first
line and joins the second only within r of the corner (the overlap lasts no
longer than the first move's remaining part, which began within r). Blends
may not overlap (the user manual: "Blends cannot overlap"): a move whose own
r and the previous waypoint's add up to more than the segment between them,
or that would start while the previous one still blends out of its own
predecessor, raises MotionError.
"""

import math

import numpy as np

from .arm_kinematics import rigid_inverse, rotation_matrix, rotation_vector
from .joints import follow

# movej(q, a=1.4, v=1.05, t=0, r=0): Module motion, movej.
MOVEJ_A, MOVEJ_V = 1.4, 1.05
# movel(pose, a=1.2, v=0.25, t=0, r=0): Module motion, movel.
MOVEL_A, MOVEL_V = 1.2, 0.25
# movep(pose, a=1.2, v=0.25, r=0): Module motion, movep.
MOVEP_A, MOVEP_V = 1.2, 0.25
# servoj(q, a, v, t=0.002, lookahead_time=0.1, gain=300): Module motion, servoj.
SERVOJ_T, SERVOJ_LOOKAHEAD_TIME, SERVOJ_GAIN = 0.002, 0.1, 300.0
# movel's tool rotation per unit of its linear speed and acceleration (rad per m): UR forum,
# "MoveL: Tool Angular Speed" (the manual states a and v in m/s and m/s^2 only).
ROTATION_PER_METRE = 4.0
# The largest joint motion (rad) between two solved path samples that is still one branch of the path.
BRANCH_JUMP = 0.5
# A Cartesian path is checked before moving at samples this far apart (m, rad).
CHECK_STEP = 0.01
# How closely (m and rad, as one norm) each cycle's joints reach the pose: far below a cycle's motion
# (2.4 um in the first 2 ms of a movel at its default a), or the commanded speed jitters.
IK_TOLERANCE = 1e-9
# Damping of the pseudo-inverse that estimates joint speeds from a tool twist.
DAMPING = 1e-3
# Joint speeds may pass the model's limits by this share before a Cartesian motion is refused
# (the inverse kinematics' residual, not a real excess).
SPEED_SLACK = 0.02


class MotionError(ValueError):
    """A motion the arm cannot make; the message is one line, as the robot's log says it."""


# -- poses ------------------------------------------------------------------------------------------

def tcp_pose(arm, tcp, q):
    """4x4 pose of the TCP (tool0 x `tcp`, a 4x4 or None for tool0) in the base for joints q."""
    pose = arm.forward(q)
    return pose if tcp is None else pose.dot(tcp)


def ur_pose_of(matrix):
    """URScript pose p[x, y, z, rx, ry, rz] (a list) of a 4x4 pose: what get_actual_tcp_pose() returns."""
    return [float(v) for v in matrix[:3, 3]] + [float(v) for v in rotation_vector(matrix[:3, :3])]


def tcp_jacobian(arm, tcp, q):
    """6x6 Jacobian of the TCP in the base (linear rows at the TCP point, then angular)."""
    jac = arm.jacobian(q)
    if tcp is None:
        return jac
    lever = arm.forward(q)[:3, :3].dot(tcp[:3, 3])
    skew = np.array([[0.0, -lever[2], lever[1]], [lever[2], 0.0, -lever[0]], [-lever[1], lever[0], 0.0]])
    return np.vstack([jac[:3] - skew.dot(jac[3:]), jac[3:]])


def _joint_speeds(jac, twist):
    """Joint speeds for a tool twist by the damped pseudo-inverse (finite near singularities)."""
    return jac.T.dot(np.linalg.solve(jac.dot(jac.T) + DAMPING ** 2 * np.eye(6), twist))


class Profile(object):
    """Trapezoid speed profile over `distance` (peak v, acceleration a; a triangle where v is not reached),
    stretched or squeezed in time to last `t` when t > 0. Times are the caller's (real) seconds."""

    def __init__(self, distance, v, a, t=0.0):
        self.distance = abs(float(distance))
        v, a = float(v), float(a)
        if self.distance <= 0.0:
            self.v, self.a, self.natural, self.ramp_natural = v, a, 0.0, 0.0
        elif self.distance >= v * v / a:
            self.v, self.a, self.ramp_natural = v, a, v / a
            self.natural = self.distance / v + v / a
        else:
            self.v, self.a = math.sqrt(self.distance * a), a
            self.ramp_natural = self.v / a
            self.natural = 2.0 * self.ramp_natural
        self.total = float(t) if t > 0.0 else self.natural
        # Natural seconds per real second.
        self.rate = self.natural / self.total if self.total > 0.0 else 1.0

    @property
    def ramp(self):
        """Real seconds of the acceleration (and of the deceleration)."""
        return self.ramp_natural / self.rate

    @property
    def peak(self):
        """Peak speed in real time."""
        return self.v * self.rate

    def covered(self, t):
        """Distance covered after t real seconds."""
        if self.distance <= 0.0 or t >= self.total:
            return self.distance
        if t <= 0.0:
            return 0.0
        t = t * self.rate
        ramp, v, a = self.ramp_natural, self.v, self.a
        if t < ramp:
            s = 0.5 * a * t * t
        elif t > self.natural - ramp:
            s = self.distance - 0.5 * a * (self.natural - t) ** 2
        else:
            s = 0.5 * a * ramp * ramp + v * (t - ramp)
        return min(self.distance, max(0.0, s))

    def fraction(self, t):
        return 1.0 if self.distance <= 0.0 else self.covered(t) / self.distance


# -- the common part ----------------------------------------------------------------------------------

class Motion(object):
    """What every motion has: its commanded joints `q` and their speeds `qd`, `returned`, `done`."""

    name = 'motion'

    def __init__(self, arm, q_start, qd_start, previous=None):
        self.arm = arm
        if previous is not None and getattr(previous, 'q', None) is not None:
            # Its commanded state; a speed motion's own speed rather than the last cycle's mean.
            q_start, qd_start = previous.q, getattr(previous, 'speed', previous.qd)
        self.q = np.array(q_start, dtype=float)
        self.qd = np.zeros(6) if qd_start is None else np.array(qd_start, dtype=float)
        self.elapsed = 0.0
        self.returned = False
        self.done = False

    def step(self, dt, q=None, qd=None):
        """The joint positions for the end of this cycle of dt seconds (q, qd: measured; not used)."""
        if dt <= 0.0 or self.done:
            if self.done:
                self.qd = np.zeros_like(self.q)
            return self.q.copy()
        new = self._advance(dt)
        self.qd = (new - self.q) / dt
        self.q = new
        self.elapsed += dt
        return self.q.copy()

    def _advance(self, dt):
        raise NotImplementedError

    def _check_limits(self, q, what):
        arm = self.arm
        beyond = np.nonzero((q < arm.lower - 1e-9) | (q > arm.upper + 1e-9))[0]
        if len(beyond):
            raise MotionError('%s: joint %d would pass its position limit (%.3f rad, limits %.3f to %.3f)'
                              % (what, beyond[0], q[beyond[0]], arm.lower[beyond[0]], arm.upper[beyond[0]]))

    def _check_speed(self, new, dt, what):
        speeds = np.abs(new - self.q) / dt
        over = np.nonzero(speeds > self.arm.velocity * (1.0 + SPEED_SLACK))[0]
        if len(over):
            raise MotionError('%s: joint %d would exceed its speed limit (%.2f rad/s, limit %.2f): the path passes '
                              'too near a singularity' % (what, over[0], speeds[over[0]], self.arm.velocity[over[0]]))


class PathMotion(Motion):
    """A move to a target (movej, movel, movep): a fixed path and time, a blend radius r, blends."""

    cartesian = False

    def __init__(self, arm, tcp, q_start, qd_start, r, previous):
        blending = isinstance(previous, PathMotion) and not previous.done
        super(PathMotion, self).__init__(arm, q_start, qd_start, previous)
        self.tcp = None if tcp is None else np.asarray(tcp, dtype=float)
        self.tcp_inverse = None if tcp is None else rigid_inverse(self.tcp)
        self.r = float(r)
        if self.r < 0.0:
            raise MotionError('%s: the blend radius r must be >= 0 m' % self.name)
        # The move being blended out of, stepped here until it ends; its target is where this one starts.
        self.previous = previous if blending else None
        self.start_q = previous.end_q if blending else self.q.copy()
        self.start_pose = previous.end_pose if blending else tcp_pose(arm, self.tcp, self.start_q)
        self.own_time = 0.0  # this move's own clock; it starts when the blend does
        self.delay = 0.0

    def _check_blends(self):
        """The user manual: "Blends cannot overlap": the blend radius at the previous waypoint (this move's
        start) and this move's own must fit on the segment between them. Called once the target is known."""
        if self.previous is None:
            return
        if self.previous.previous is not None:
            raise MotionError('%s: overlapping blends: the previous move is still blending out of the one '
                              'before it; use smaller blend radii' % self.name)
        length = float(np.linalg.norm(self.end_pose[:3, 3] - self.start_pose[:3, 3]))
        if self.r > 0.0 and self.previous.r + self.r > length:
            raise MotionError('%s: overlapping blends: r=%g at the previous waypoint and r=%g here overlap on '
                              'the %.3f m between them; make their sum at most that' % (
                                  self.name, self.previous.r, self.r, length))

    def _blend_delay(self):
        """Seconds this move waits while the previous one goes on alone: until the previous has only this
        move's acceleration time left, so that its deceleration and this acceleration overlap exactly."""
        if self.previous is None:
            return 0.0
        return max(0.0, self.previous.remaining() - self.ramp_time())

    def remaining(self):
        return max(0.0, self.total_time - self.own_time)

    def tool_distance_to_target(self):
        return float(np.linalg.norm(tcp_pose(self.arm, self.tcp, self.q)[:3, 3] - self.end_pose[:3, 3]))

    def _finish_step(self):
        own_done = self.own_time >= self.total_time
        previous_done = self.previous is None or self.previous.done
        if previous_done and self.previous is not None:
            self.previous = None
        self.done = own_done and previous_done
        if self.done:
            self.returned = True
        elif self.r > 0.0 and not self.returned and self.previous is None:
            self.returned = self.tool_distance_to_target() <= self.r

    def step(self, dt, q=None, qd=None):
        if dt > 0.0 and not self.done and self.elapsed == 0.0:
            self.delay = self._blend_delay()
        result = super(PathMotion, self).step(dt, q, qd)
        if dt > 0.0:
            self._finish_step()
        return result

    def _own_clock(self, dt):
        """Advance this move's clock by the part of dt after its blend delay."""
        start = max(0.0, self.delay - self.elapsed)
        self.own_time = min(self.total_time, self.own_time + max(0.0, dt - start))
        return self.own_time

    def _advance(self, dt):
        t = self._own_clock(dt)
        previous = self.previous
        if previous is None:
            return self._alone(t, dt)
        if self.cartesian and previous.cartesian:
            previous._tick(dt)
            mine = self.pose_at(t)
            pose = previous.pose_at(previous.own_time)
            pose[:3, 3] += mine[:3, 3] - self.start_pose[:3, 3]
            pose[:3, :3] = mine[:3, :3].dot(self.start_pose[:3, :3].T).dot(pose[:3, :3])
            new = self._solve(pose, self.q, dt)
            if previous.own_time >= previous.total_time:
                previous.done = True
            return new
        # Joint space: the previous move's joints plus this move's displacement from its start.
        theirs = previous.step(dt)
        return theirs + (self._own_joints(t, dt) - self.start_q)

    def _tick(self, dt):
        """Advance only the clock (a Cartesian move whose pose another move solves)."""
        self.own_time = min(self.total_time, self.own_time + dt)
        self.elapsed += dt

    def _alone(self, t, dt):
        raise NotImplementedError

    def _own_joints(self, t, dt):
        raise NotImplementedError


# -- movej ---------------------------------------------------------------------------------------------

class JointMove(PathMotion):
    """movej(q, a=1.4, v=1.05, t=0, r=0); q_target in joint positions (a pose: inverse kinematics first)."""

    name = 'movej'

    def __init__(self, arm, q_start, qd_start, q_target, a=MOVEJ_A, v=MOVEJ_V, t=0.0, r=0.0, tcp=None,
                 previous=None):
        super(JointMove, self).__init__(arm, tcp, q_start, qd_start, r, previous)
        target = np.array(q_target, dtype=float)
        if target.shape != (6,) or not np.all(np.isfinite(target)):
            raise MotionError('movej: q must be six finite joint positions')
        if not (a > 0 and v > 0 and t >= 0):
            raise MotionError('movej: a > 0, v > 0 and t >= 0')
        self._check_limits(target, 'movej')
        self.end_q = target
        self.end_pose = tcp_pose(arm, self.tcp, target)
        self._check_blends()
        self.delta = target - self.start_q
        distance = float(np.max(np.abs(self.delta)))
        ratios = np.abs(self.delta) / max(distance, 1e-12)
        # No joint beyond its speed limit: the leading joint's speed is capped by the tightest ratio.
        cap = min([float(limit) / ratio for limit, ratio in zip(arm.velocity, ratios) if ratio > 1e-9] or [v])
        self.profile = Profile(distance, min(v, cap), a, t)
        if self.profile.peak > cap * (1.0 + 1e-9):
            # t asked for more speed than a joint has: as fast as the joints go, the natural profile
            # squeezed until its peak is the cap.
            self.profile = Profile(distance, min(v, cap), a, self.profile.natural * self.profile.v / cap)
        self.total_time = self.profile.total

    def ramp_time(self):
        return self.profile.ramp

    def position(self, t):
        """Joint positions t seconds into the move (alone): the old urscript.JointMove's call."""
        return self.start_q + self.delta * self.profile.fraction(t)

    def _alone(self, t, dt):
        return self.position(t)

    def _own_joints(self, t, dt):
        return self.position(t)


# -- movel, movep ------------------------------------------------------------------------------------

class LinearMove(PathMotion):
    """movel(pose, a=1.2, v=0.25, t=0, r=0): `target_pose` the TCP's 4x4 pose in the base, `tcp` tool0 ->
    TCP (4x4, None: tool0)."""

    name = 'movel'
    cartesian = True

    def __init__(self, arm, tcp, q_start, qd_start, target_pose, a=MOVEL_A, v=MOVEL_V, t=0.0, r=0.0,
                 previous=None):
        super(LinearMove, self).__init__(arm, tcp, q_start, qd_start, r, previous)
        target = np.array(target_pose, dtype=float)
        if target.shape != (4, 4) or not np.all(np.isfinite(target)):
            raise MotionError('%s: the pose must be a finite 4x4 transform' % self.name)
        if not (a > 0 and v > 0 and t >= 0):
            raise MotionError('%s: a > 0, v > 0 and t >= 0' % self.name)
        self.end_pose = target
        self._check_blends()
        self._plan(a, v, t)
        self.end_q = self._check_path()
        self._nominal_q = self.start_q.copy()  # this move's own joints, for a blend in joint space

    def _plan(self, a, v, t):
        """The straight line and slerp from the start pose to the target and their common profile."""
        start, end = self.start_pose, self.end_pose
        self.line = end[:3, 3] - start[:3, 3]
        self.turn = rotation_vector(end[:3, :3].dot(start[:3, :3].T))
        length, angle = float(np.linalg.norm(self.line)), float(np.linalg.norm(self.turn))
        linear = Profile(length, v, a)
        angular = Profile(angle, ROTATION_PER_METRE * v, ROTATION_PER_METRE * a)
        leading = linear if linear.natural >= angular.natural else angular
        self.profile = Profile(leading.distance, leading.v, leading.a, t)
        self.total_time = self.profile.total
        self.check_length = max(length, angle)

    def ramp_time(self):
        return self.profile.ramp

    def pose_at(self, t):
        """The TCP's pose t seconds into this move (alone)."""
        return self._pose_at_fraction(self.profile.fraction(t))

    def _pose_at_fraction(self, fraction):
        pose = np.eye(4)
        pose[:3, 3] = self.start_pose[:3, 3] + fraction * self.line
        pose[:3, :3] = rotation_matrix(fraction * self.turn).dot(self.start_pose[:3, :3])
        return pose

    def _check_path(self):
        """The joints at the end, found along the path from the start; MotionError where the path leaves the
        reach or jumps between branches (where the robot would stop)."""
        steps = max(1, int(math.ceil(self.check_length / CHECK_STEP)))
        q = self.start_q
        for k in range(1, steps + 1):
            pose = self._pose_at_fraction(float(k) / steps)
            found = self.arm.inverse(self._tool0(pose), q, tolerance=IK_TOLERANCE)
            if found is None:
                where = 'the target pose' if k == steps else 'the path at (%.3f, %.3f, %.3f)' % tuple(pose[:3, 3])
                raise MotionError('%s: %s is out of reach of the arm (no inverse kinematics solution)'
                                  % (self.name, where))
            if np.max(np.abs(found - q)) > BRANCH_JUMP:
                raise MotionError('%s: the path passes a singularity near (%.3f, %.3f, %.3f)'
                                  % ((self.name,) + tuple(pose[:3, 3])))
            q = found
        return q

    def _tool0(self, pose):
        return pose if self.tcp_inverse is None else pose.dot(self.tcp_inverse)

    def _solve(self, pose, seed, dt):
        """Joints reaching the TCP `pose` from `seed`; dt > 0: checked against the joints' speed limits."""
        found = self.arm.inverse(self._tool0(pose), seed, tolerance=IK_TOLERANCE)
        if found is None:
            raise MotionError('%s: the path leaves the reach of the arm at (%.3f, %.3f, %.3f)'
                              % ((self.name,) + tuple(pose[:3, 3])))
        self._check_limits(found, self.name)
        if dt > 0.0:
            self._check_speed(found, dt, self.name)
        return found

    def _alone(self, t, dt):
        return self._solve(self.pose_at(t), self.q, dt)

    def _own_joints(self, t, dt):
        self._nominal_q = self._solve(self.pose_at(t), self._nominal_q, 0.0)
        return self._nominal_q

    def tool_speed(self):
        """The TCP's commanded linear velocity (m/s, base frame)."""
        return tcp_jacobian(self.arm, self.tcp, self.q)[:3].dot(self.qd)


class ProcessMove(LinearMove):
    """movep(pose, a=1.2, v=0.25, r=0): a straight line at constant tool speed; blended from another movep
    through a circular arc, from where the tool is, at the speed it has, tangent to both lines."""

    name = 'movep'

    def __init__(self, arm, tcp, q_start, qd_start, target_pose, a=MOVEP_A, v=MOVEP_V, r=0.0, previous=None):
        self.arc = None
        super(ProcessMove, self).__init__(arm, tcp, q_start, qd_start, target_pose, a, v, 0.0, r, previous)

    def _plan(self, a, v, t):
        super(ProcessMove, self)._plan(a, v, t)
        previous = self.previous
        if isinstance(previous, ProcessMove):
            self._plan_arc(previous, a, v)

    def _plan_arc(self, previous, a, v):
        """The previous move's rest replaced by an arc tangent to both lines, then the rest of this line;
        nothing changes where there is no room for an arc (the superposed blend then)."""
        corner = previous.end_pose[:3, 3]
        here = tcp_pose(self.arm, self.tcp, previous.q)
        inbound = previous.line / max(float(np.linalg.norm(previous.line)), 1e-12)
        outbound = self.end_pose[:3, 3] - corner
        length = float(np.linalg.norm(outbound))
        cut = float(np.dot(corner - here[:3, 3], inbound))
        if length <= 1e-9 or cut <= 1e-6 or cut >= length:
            return
        outbound = outbound / length
        cosine = float(np.clip(np.dot(inbound, outbound), -1.0, 1.0))
        if cosine > 1.0 - 1e-9 or cosine < -1.0 + 1e-6:
            return  # straight on, or straight back: no arc
        turn = math.acos(cosine)  # how far the path's direction turns
        radius = cut / math.tan(turn / 2.0)
        inward = outbound - cosine * inbound
        start = corner - cut * inbound
        centre = start + radius * inward / np.linalg.norm(inward)
        spoke = start - centre
        axis = np.cross(spoke, inbound)
        self.arc = (centre, spoke, axis / np.linalg.norm(axis), radius)
        self.arc_length = radius * turn
        self.line_start = corner + cut * outbound
        self.line_length = length - cut
        self.path_length = self.arc_length + self.line_length
        # The previous move ends here: this one starts where the tool is, at its speed.
        speed = float(np.linalg.norm(previous.tool_speed()))
        self.previous = None
        self.q, self.qd = previous.q.copy(), previous.qd.copy()
        self.start_q, self.start_pose = previous.q.copy(), here
        self.turn = rotation_vector(self.end_pose[:3, :3].dot(here[:3, :3].T))
        self.speed_profile = StartSpeedProfile(self.path_length, speed, v, a)
        self.total_time = self.speed_profile.total
        self.check_length = max(self.path_length, float(np.linalg.norm(self.turn)))

    def pose_at(self, t):
        if self.arc is None:
            return super(ProcessMove, self).pose_at(t)
        return self._pose_at_fraction(self.speed_profile.covered(t) / self.path_length)

    def _pose_at_fraction(self, fraction):
        if self.arc is None:
            return super(ProcessMove, self)._pose_at_fraction(fraction)
        centre, spoke, axis, radius = self.arc
        s = fraction * self.path_length
        pose = np.eye(4)
        if s < self.arc_length:
            pose[:3, 3] = centre + rotation_matrix(axis * (s / radius)).dot(spoke)
        else:
            direction = (self.end_pose[:3, 3] - self.line_start) / max(self.line_length, 1e-12)
            pose[:3, 3] = self.line_start + direction * (s - self.arc_length)
        pose[:3, :3] = rotation_matrix(fraction * self.turn).dot(self.start_pose[:3, :3])
        return pose


class StartSpeedProfile(object):
    """Speed profile over `distance` from speed v0: to v (at a), on at v, down to rest at the end (at a, or
    harder where the distance is too short to stop in at a)."""

    def __init__(self, distance, v0, v, a):
        self.distance, self.v0, self.a = float(distance), max(0.0, float(v0)), float(a)
        v0 = self.v0
        if v0 * v0 / (2.0 * a) >= distance:
            self.peak, self.t1, self.s1, self.cruise = v0, 0.0, 0.0, 0.0
            self.decel = v0 * v0 / (2.0 * max(distance, 1e-12))
        else:
            # v if there is room, else where the acceleration from v0 meets the deceleration to rest.
            self.peak = max(v0, min(float(v), math.sqrt((2.0 * a * distance + v0 * v0) / 2.0)))
            self.t1 = (self.peak - v0) / a
            self.s1 = (self.peak ** 2 - v0 * v0) / (2.0 * a)
            self.decel = a
            self.cruise = max(0.0, distance - self.s1 - self.peak ** 2 / (2.0 * a)) / self.peak
        self.total = self.t1 + self.cruise + (self.peak / self.decel if self.peak > 0.0 else 0.0)

    def covered(self, t):
        if t >= self.total:
            return self.distance
        if t <= self.t1:
            return self.v0 * t + 0.5 * self.a * t * t
        if t <= self.t1 + self.cruise:
            return self.s1 + self.peak * (t - self.t1)
        left = self.total - t
        return self.distance - 0.5 * self.decel * left * left


# -- speedl, stopl, speedj, stopj, servoj ------------------------------------------------------------

class SpeedMotion(Motion):
    """What speedl and speedj share: their return, after each cycle."""

    def step(self, dt, q=None, qd=None):
        result = super(SpeedMotion, self).step(dt, q, qd)
        self._update_returned()
        return result

    def _update_returned(self):
        """After t if given (t_min on older software: after t and at speed), else on reaching the speed."""
        if self.t > 0.0 and not self.minimum_time:
            self.returned = self.returned or self.elapsed >= self.t - 1e-9
        else:
            self.returned = self.returned or (self.reached and self.elapsed >= self.t - 1e-9)


class ToolSpeed(SpeedMotion):
    """speedl(xd, a, t, aRot='a'): xd the tool twist (base frame: m/s, then rad/s) to accelerate to."""

    name = 'speedl'

    def __init__(self, arm, tcp, q_start, qd_start, xd, a, t=0.0, aRot=None, minimum_time=False, previous=None):
        super(ToolSpeed, self).__init__(arm, q_start, qd_start, previous)
        self.tcp = None if tcp is None else np.asarray(tcp, dtype=float)
        self.tcp_inverse = None if tcp is None else rigid_inverse(self.tcp)
        target = np.array(xd, dtype=float)
        if target.shape != (6,) or not np.all(np.isfinite(target)):
            raise MotionError('%s: xd must be six finite numbers' % self.name)
        a_rot = a if aRot is None else aRot
        if not (a > 0 and a_rot > 0 and t >= 0):
            raise MotionError('%s: a > 0, aRot > 0 and t >= 0' % self.name)
        self.target, self.a, self.a_rot = target, float(a), float(a_rot)
        self.t, self.minimum_time = float(t), bool(minimum_time)
        self.pose = tcp_pose(arm, self.tcp, self.q)
        twist = getattr(previous, 'twist', None)
        self.twist = np.array(twist, dtype=float) if twist is not None else \
            tcp_jacobian(arm, self.tcp, self.q).dot(self.qd)
        self.reached = False

    def _ramp(self, dt):
        """This cycle's twist: toward the target, linear part at a, angular at aRot, arriving together."""
        change = self.target - self.twist
        time_left = max(np.linalg.norm(change[:3]) / self.a, np.linalg.norm(change[3:]) / self.a_rot)
        if time_left <= dt:
            return self.target.copy(), True
        return self.twist + change * (dt / time_left), False

    def _advance(self, dt):
        twist, reached = self._ramp(dt)
        # Within the joints' speed limits: the whole twist scaled down alike, first by the Jacobian's
        # estimate, then by the solved step itself (the estimate is a linearisation).
        speeds = np.abs(_joint_speeds(tcp_jacobian(self.arm, self.tcp, self.q), twist))
        excess = float(np.max(speeds / self.arm.velocity))
        if excess > 1.0:
            twist, reached = twist / excess, False
        for _ in range(3):
            pose, found = self._solve(twist, dt)
            excess = float(np.max(np.abs(found - self.q) / (self.arm.velocity * dt)))
            if excess <= 1.0:
                break
            # The mean of the cycle's twist sets the step: scale the end twist so that the mean shrinks alike.
            mean = 0.5 * (self.twist + twist) / excess
            twist, reached = 2.0 * mean - self.twist, False
        self._check_limits(found, self.name)
        self.pose, self.twist = pose, twist
        self.reached = self.reached or reached
        return found

    def _solve(self, twist, dt):
        """(TCP pose, joints) after a cycle whose twist goes linearly from the last one to `twist`."""
        mean = 0.5 * (self.twist + twist)
        pose = self.pose.copy()
        pose[:3, 3] += mean[:3] * dt
        pose[:3, :3] = rotation_matrix(mean[3:] * dt).dot(pose[:3, :3])
        target = pose if self.tcp_inverse is None else pose.dot(self.tcp_inverse)
        found = self.arm.inverse(target, self.q, tolerance=IK_TOLERANCE)
        if found is None:
            raise MotionError('%s: the tool leaves the reach of the arm at (%.3f, %.3f, %.3f)'
                              % ((self.name,) + tuple(pose[:3, 3])))
        return pose, found



class ToolStop(ToolSpeed):
    """stopl(a, aRot='a'): the tool twist down to zero, linear part at a, angular at aRot; returns at rest."""

    name = 'stopl'

    def __init__(self, arm, tcp, q_start, qd_start, a, aRot=None, previous=None):
        super(ToolStop, self).__init__(arm, tcp, q_start, qd_start, np.zeros(6), a, 0.0, aRot, previous=previous)

    def _update_returned(self):
        if self.reached:
            self.returned = self.done = True


class JointSpeed(SpeedMotion):
    """speedj(qd, a, t): the joint speeds to accelerate to, a the leading joint's acceleration."""

    name = 'speedj'

    def __init__(self, arm, q_start, qd_start, qd, a, t=0.0, minimum_time=False, previous=None):
        super(JointSpeed, self).__init__(arm, q_start, qd_start, previous)
        target = np.array(qd, dtype=float)
        if target.shape != (6,) or not np.all(np.isfinite(target)):
            raise MotionError('%s: qd must be six finite joint speeds' % self.name)
        if not (a > 0 and t >= 0):
            raise MotionError('%s: a > 0 and t >= 0' % self.name)
        # Within the joints' speed limits: the whole target scaled down alike.
        excess = float(np.max(np.abs(target) / arm.velocity))
        self.target = target / excess if excess > 1.0 else target
        self.a, self.t, self.minimum_time = float(a), float(t), bool(minimum_time)
        self.speed = self.qd.copy()  # the joint speeds at the end of the last cycle (qd: its mean)
        self.reached = False

    def _advance(self, dt):
        change = self.target - self.speed
        time_left = float(np.max(np.abs(change))) / self.a
        if time_left <= dt:
            speed, reached = self.target.copy(), True
        else:
            speed, reached = self.speed + change * (dt / time_left), False
        new = self.q + 0.5 * (self.speed + speed) * dt
        self._check_limits(new, self.name)
        self.speed, self.reached = speed, self.reached or reached
        return new



class JointStop(JointSpeed):
    """stopj(a): the joint speeds down to zero, the leading joint at a; returns at rest."""

    name = 'stopj'

    def __init__(self, arm, q_start, qd_start, a, previous=None):
        super(JointStop, self).__init__(arm, q_start, qd_start, np.zeros(6), a, previous=previous)

    def _update_returned(self):
        if self.reached:
            self.returned = self.done = True


class Servo(Motion):
    """servoj(q, a, v, t=0.002, lookahead_time=0.1, gain=300): the joints follow q as a first-order lag with
    the lookahead time as time constant, within their speed limits; returns (and ends) after t."""

    name = 'servoj'

    def __init__(self, arm, q_start, qd_start, q, a=0.0, v=0.0, t=SERVOJ_T, lookahead_time=SERVOJ_LOOKAHEAD_TIME,
                 gain=SERVOJ_GAIN, previous=None):
        super(Servo, self).__init__(arm, q_start, qd_start, previous)
        target = np.array(q, dtype=float)
        if target.shape != (6,) or not np.all(np.isfinite(target)):
            raise MotionError('servoj: q must be six finite joint positions')
        if not (t > 0 and lookahead_time > 0):
            raise MotionError('servoj: t > 0 and lookahead_time > 0')
        self._check_limits(target, 'servoj')
        self.target, self.t, self.lookahead_time = target, float(t), float(lookahead_time)

    def _advance(self, dt):
        moved, _ = follow(self.q, self.target, dt, self.lookahead_time, self.arm.velocity, self.arm.lower,
                          self.arm.upper)
        return moved

    def step(self, dt, q=None, qd=None):
        result = super(Servo, self).step(dt, q, qd)
        if self.elapsed >= self.t - 1e-9:
            self.returned = self.done = True
        return result
