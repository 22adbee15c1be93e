"""A joint trajectory controller's goals over time, scaled or not, without ROS.

The node calls accept() for a new goal, cancel() for a cancel request and
update() every control cycle; each returns what happened to which goal, and
the node turns that into actionlib results. Time here is the controller's
own trajectory time: the scaled controllers (ur_robot_driver's
ScaledJointTrajectoryController) advance it by the period times the speed
scaling, so a slider at 50 % runs the trajectory at half speed and a paused
program (scaling 0) holds it where it is.

Velocity limits: the scaled controllers slow a trajectory down until no
joint moves faster than its limit from the model (the robot reports that as
speed scaling below the slider's value); the unscaled ones command the
trajectory as given, the joints cannot follow faster than their limits, and
the path tolerance ends the goal (PATH_TOLERANCE_VIOLATED).
"""

import numpy as np

from .trajectory import GoalError, Spline, Tolerances, stop_spline, validate_points


class Outcome(object):
    """What became of a goal: status 'succeeded', 'aborted' or 'preempted', with the result code's name."""

    def __init__(self, goal_id, status, code, message):
        self.goal_id = goal_id
        self.status = status
        self.code = code
        self.message = message

    def __repr__(self):
        return 'Outcome(%r, %s, %s, %r)' % (self.goal_id, self.status, self.code, self.message)


class _Goal(object):
    def __init__(self, goal_id, spline, tolerances, explicit_goal_time, wall_deadline):
        self.goal_id = goal_id
        self.spline = spline
        self.tolerances = tolerances
        self.explicit_goal_time = explicit_goal_time
        self.wall_deadline = wall_deadline


class TrajectoryController(object):
    """One FollowJointTrajectory controller of ur_robot_driver's config (scaled or not)."""

    def __init__(self, joints, constraints, stop_trajectory_duration, scaled, lower, upper, velocity_limits):
        self.joints = list(joints)
        self.tolerances = Tolerances.from_constraints(self.joints, constraints)
        self.stop_trajectory_duration = float(stop_trajectory_duration)
        self.scaled = scaled
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.velocity_limits = np.asarray(velocity_limits, dtype=float)
        self.clock = 0.0          # trajectory time, s
        self.wall = 0.0           # time since start, s, unscaled
        self.goal = None
        self.spline = None        # what is commanded: the goal's, or a stop, or None (hold the start)
        self.limit_factor = 1.0   # < 1 while a scaled trajectory is slowed to respect velocity limits

    # -- goals -----------------------------------------------------------------

    def accept(self, goal_id, joint_names, points, start_delay, position, velocity,
               path_tolerance=(), goal_tolerance=(), goal_time_tolerance=0.0):
        """Take a new goal; raises GoalError. Returns the Outcome of the goal it preempts, or None.

        `start_delay`: header.stamp minus now, s (0 for a zero stamp).
        `position`/`velocity`: the joints' current state, controller order.
        """
        times, positions, velocities, accelerations = validate_points(
            self.joints, joint_names, points, self.lower, self.upper)
        start = self.clock + max(0.0, start_delay)
        current = np.asarray(position, dtype=float)
        current_velocity = np.asarray(velocity, dtype=float) if velocities is not None else np.zeros_like(current)
        if times[0] > 0.0:
            times = np.concatenate([[0.0], times])
            positions = np.vstack([current, positions])
            if velocities is not None:
                velocities = np.vstack([current_velocity, velocities])
            if accelerations is not None:
                accelerations = np.vstack([np.zeros_like(current), accelerations])
        spline = Spline(start + times, positions, velocities, accelerations)
        tolerances = self.tolerances.for_goal(self.joints, path_tolerance, goal_tolerance, goal_time_tolerance)
        duration = start + times[-1] - self.clock
        preempted = None
        if self.goal is not None:
            preempted = Outcome(self.goal.goal_id, 'preempted', 'SUCCESSFUL', 'Preempted by a new goal')
        self.goal = _Goal(goal_id, spline, tolerances, goal_time_tolerance > 0.0,
                          self.wall + duration + tolerances.goal_time)
        self.spline = spline
        return preempted

    def cancel(self, goal_id, position, velocity):
        """Stop the goal `goal_id` within stop_trajectory_duration; its Outcome, or None if not active."""
        if self.goal is None or self.goal.goal_id != goal_id:
            return None
        self.goal = None
        self.spline = stop_spline(self.clock, position, velocity, self.stop_trajectory_duration)
        return Outcome(goal_id, 'preempted', 'SUCCESSFUL', 'Canceled: stopping within %g s'
                       % self.stop_trajectory_duration)

    def stop(self, position, velocity):
        """The controller is stopped (switch, program stopped): its goal is preempted, the joints stop.

        As joint_trajectory_controller's stopping(), which cancels the active goal.
        """
        outcome = None
        if self.goal is not None:
            outcome = Outcome(self.goal.goal_id, 'preempted', 'SUCCESSFUL',
                              'Controller stopped while the goal was active')
        self.goal = None
        self.spline = stop_spline(self.clock, position, velocity, self.stop_trajectory_duration)
        return outcome

    def start(self, position):
        """The controller starts: it holds the joints where they are."""
        self.goal = None
        self.spline = Spline([self.clock], [np.asarray(position, dtype=float)])

    # -- the control cycle -----------------------------------------------------

    def update(self, dt, scaling, position, velocity):
        """One cycle: (commanded position, commanded velocity, [Outcome...]).

        `scaling`: the robot's speed scaling without this controller's own
        velocity-limit factor (slider x program running); the unscaled
        controllers ignore it. `position`/`velocity`: actual joint state.
        """
        position = np.asarray(position, dtype=float)
        velocity = np.asarray(velocity, dtype=float)
        if self.spline is None:
            self.start(position)
        rate = scaling if self.scaled else 1.0
        self.limit_factor = 1.0
        if self.scaled and rate > 0.0:
            desired_velocity = self.spline.sample(self.clock)[1]
            ahead_velocity = self.spline.sample(self.clock + dt * rate)[1]
            fastest = np.max(np.maximum(np.abs(desired_velocity), np.abs(ahead_velocity)) * rate
                             / self.velocity_limits)
            if fastest > 1.0:
                self.limit_factor = 1.0 / fastest
                rate /= fastest
        self.clock += dt * rate
        self.wall += dt
        desired, desired_velocity, _ = self.spline.sample(self.clock)
        outcomes = []
        if self.goal is not None:
            outcome = self._check(desired, position, velocity)
            if outcome is not None:
                outcomes.append(outcome)
        return desired, desired_velocity * rate, outcomes

    def _check(self, desired, position, velocity):
        goal = self.goal
        tolerances = goal.tolerances
        end = goal.spline.end_time
        if self.clock < end:
            bad = Tolerances.violated(desired - position, tolerances.path_position)
            if bad.size:
                j = bad[0]
                return self._finish('aborted', 'PATH_TOLERANCE_VIOLATED',
                                    '%s is %.4f rad off the trajectory (path tolerance %g)'
                                    % (self.joints[j], abs(desired[j] - position[j]),
                                       tolerances.path_position[j]), position, velocity)
            return self._late(goal, position, velocity)
        final = goal.spline.positions[-1]
        bad_position = Tolerances.violated(final - position, tolerances.goal_position)
        bad_velocity = Tolerances.violated(velocity, tolerances.goal_velocity)
        if not bad_position.size and not bad_velocity.size:
            self.goal = None
            return Outcome(goal.goal_id, 'succeeded', 'SUCCESSFUL', '')
        late = self._late(goal, position, velocity)
        if late is not None:
            return late
        if self.clock > end + tolerances.goal_time:
            j = bad_position[0] if bad_position.size else bad_velocity[0]
            return self._finish('aborted', 'GOAL_TOLERANCE_VIOLATED',
                                '%s is %.4f rad from its goal, moving at %.4f rad/s, %g s after the '
                                'trajectory ended (goal_time tolerance)' % (
                                    self.joints[j], abs(final[j] - position[j]), velocity[j],
                                    tolerances.goal_time), position, velocity)
        return None

    def _late(self, goal, position, velocity):
        # ur_robot_driver's controllers.md: a trajectory with time constraints that the
        # scaling slowed down fails; without them, it succeeds when it arrives.
        if self.scaled and goal.explicit_goal_time and self.wall > goal.wall_deadline:
            return self._finish('aborted', 'GOAL_TOLERANCE_VIOLATED',
                                'The trajectory was slowed down by speed scaling beyond its goal_time_tolerance '
                                '(%g s)' % goal.tolerances.goal_time, position, velocity)
        return None

    def _finish(self, status, code, message, position, velocity):
        goal_id = self.goal.goal_id
        self.goal = None
        self.spline = stop_spline(self.clock, position, velocity, self.stop_trajectory_duration)
        return Outcome(goal_id, status, code, message)


__all__ = ['GoalError', 'Outcome', 'TrajectoryController']
