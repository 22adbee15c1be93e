"""Simulated Robotiq 2F-140: moves finger_joint toward the commanded opening.

Subscribes ``gripper/command`` (std_msgs/Float64): the opening between the
fingers in metres, 0.0 (closed) to 0.140 (open), the device's stroke.
Publishes at ``~rate`` ``gripper/joint_states`` (sensor_msgs/JointState, the
one joint ``<prefix>finger_joint``; the mimic joints follow it in
robot_state_publisher / joint_state_publisher) and ``gripper/opening``
(std_msgs/Float64, the current opening on the same 0..0.140 scale).

The opening moves toward the last valid command at ``~speed`` m/s. The
opening -> finger_joint mapping comes from the model's own finger kinematics
(gripper_model.GripperKinematics, read from ``robot_description``): 0.140 is
0.0 rad (open), 0.0 is the joint's upper limit (closed); see that class for
how the nominal stroke maps onto the model's pad gap.

A NaN, infinite or out-of-range command is ignored with one warning naming
the valid range; the node keeps its last valid target. The warning is given
once per kind of bad command (not a number, infinite, below 0, above the
stroke) and again only after a valid command came in between and at least
REWARN_AFTER seconds later, so neither a flood of bad commands nor one that
alternates bad and good ones can flood the log.

Private parameters (defaults from config/sim_devices.yaml):
  ~prefix            ''  ; prefix of the model's joints
  ~rate              50 Hz
  ~speed             0.250 m/s (the 2F-140's maximum closing speed)
  ~initial_opening   0.140 m (open, like finger_joint = 0)
  ~devices_file      config/sim_devices.yaml
"""

import math
import time

from ur3_ft_gripper_description import gripper_model, node_loop, sim_params

# Fine enough that the interpolated angle is within 1e-6 rad of the exact
# inverse (test_sim_models checks it), cheap enough to build at start-up.
ANGLE_TABLE_SAMPLES = 4001

# A kind of bad command is warned about at most once per this many seconds.
REWARN_AFTER = 1.0


def command_problem(value, stroke):
    """None if `value` is a valid opening command, else (kind, description)."""
    if math.isnan(value):
        return 'nan', 'not a number'
    if math.isinf(value):
        return 'inf', 'infinite'
    if value < 0.0:
        return 'below', 'below 0.0 (closed)'
    if value > stroke:
        return 'above', 'above %g (open)' % stroke
    return None


class GripperState(object):
    """Target and current opening, and the motion between them (no ROS)."""

    def __init__(self, stroke, speed, initial_opening, log_warn, clock=time.monotonic):
        self.stroke = stroke
        self.speed = speed
        self.opening = initial_opening
        self.target = initial_opening
        self._warn = log_warn
        self._clock = clock
        self._warned = set()   # kinds warned about since the last valid command
        self._last_warning = {}  # kind -> clock() of its last warning

    def command(self, value):
        """Take `value` as the new target if valid; returns whether it was taken."""
        value = float(value)
        problem = command_problem(value, self.stroke)
        if problem is None:
            self.target = value
            self._warned.clear()
            return True
        kind, what = problem
        now = self._clock()
        if kind not in self._warned and now - self._last_warning.get(kind, -math.inf) >= REWARN_AFTER:
            self._warned.add(kind)
            self._last_warning[kind] = now
            self._warn('gripper_sim: ignored gripper/command %r: %s; the opening must be between '
                       '0.0 (closed) and %g (open) m. Keeping the target %.4f m.'
                       % (value, what, self.stroke, self.target))
        return False

    def advance(self, dt):
        """Move toward the target for `dt` seconds; returns the new opening."""
        self.opening = gripper_model.step_toward(self.opening, self.target, self.speed, max(dt, 0.0))
        return self.opening


def settings_from_params(get_param):
    """(prefix, rate, speed, stroke, initial_opening, warnings) from private parameters."""
    spec = sim_params.from_devices_file(get_param, gripper_model.load_gripper_spec)
    prefix = sim_params.prefix(get_param)
    stroke = spec['stroke']
    speed = sim_params.number(get_param, '~speed', spec.get('max_speed', 0.25), strictly_above=0.0)
    initial = sim_params.number(get_param, '~initial_opening', stroke, minimum=0.0)
    if initial > stroke:
        raise sim_params.ParamError('~initial_opening=%r must be between 0.0 and %g' % (initial, stroke))
    notes = []
    low, high = spec.get('min_speed'), spec.get('max_speed')
    if low is not None and high is not None and not low <= speed <= high:
        notes.append('gripper_sim: ~speed=%g m/s is outside the real 2F-140 range %g..%g m/s'
                     % (speed, low, high))
    return dict(prefix=prefix, stroke=stroke, speed=speed, initial_opening=initial,
                rate=sim_params.number(get_param, '~rate', 50.0, strictly_above=0.0),
                notes=notes)


def run(rospy):
    """The node: parameters, model, subscriber, publish loop. Returns the exit status."""
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64

    try:
        settings = settings_from_params(rospy.get_param)
    except sim_params.ParamError as exc:
        rospy.logfatal('gripper_sim: bad parameter %s', exc)
        return 1
    for note in settings['notes']:
        rospy.logwarn(note)
    if not rospy.has_param('robot_description'):
        rospy.logfatal('gripper_sim: no robot_description parameter: load the model first '
                       '(load_ur3_ft_gripper.launch), the finger kinematics come from it')
        return 1
    try:
        fingers = gripper_model.GripperKinematics(rospy.get_param('robot_description'),
                                                  prefix=settings['prefix'], stroke=settings['stroke'],
                                                  samples=ANGLE_TABLE_SAMPLES)
    except ValueError as exc:
        rospy.logfatal('gripper_sim: robot_description has no usable 2F-140 (%s); check ~prefix', exc)
        return 1

    state = GripperState(settings['stroke'], settings['speed'], settings['initial_opening'],
                         rospy.logwarn)
    joint_publisher = rospy.Publisher('gripper/joint_states', JointState, queue_size=10)
    opening_publisher = rospy.Publisher('gripper/opening', Float64, queue_size=10)
    rospy.Subscriber('gripper/command', Float64, lambda msg: state.command(msg.data), queue_size=100)
    rospy.loginfo('gripper_sim: %s at %.4f m; commands on gripper/command (0.0 closed .. %g open)',
                  fingers.joint_name, state.opening, settings['stroke'])

    def angle_of(opening):
        return fingers.table_angle(fingers.command_to_opening(opening))

    clock = {'time': rospy.Time.now(), 'angle': angle_of(state.opening)}

    def step():
        now = rospy.Time.now()
        dt = (now - clock['time']).to_sec()
        opening = state.advance(dt)
        angle = angle_of(opening)
        joint_state = JointState()
        joint_state.header.stamp = now
        joint_state.name = [fingers.joint_name]
        joint_state.position = [angle]
        joint_state.velocity = [(angle - clock['angle']) / dt if dt > 0 else 0.0]
        clock['time'], clock['angle'] = now, angle
        joint_publisher.publish(joint_state)
        opening_publisher.publish(Float64(opening))

    def restart_clock():
        clock['time'] = rospy.Time.now()

    return node_loop.run_at_rate(rospy, settings['rate'], step, on_time_jump=restart_clock)


def main():
    import rospy
    rospy.init_node('gripper_sim')
    return run(rospy)
