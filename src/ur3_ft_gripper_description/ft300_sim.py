"""Simulated Robotiq FT 300: what the real sensor reads when nothing touches the tool.

Publishes ``robotiq_ft_wrench`` (geometry_msgs/WrenchStamped), the topic of
the real driver (robotiq_ft_sensor's ``rq_sensor``), in ``~frame_id``: the
weight of the gripper (and of a held object) as it acts on the sensor for the
current pose, taken from TF, plus white noise, minus the zero offset that the
``robotiq_ft_zero`` service (std_srvs/Trigger) sets.

Private parameters (defaults from config/sim_devices.yaml):
  ~prefix          '' ; prefix of the model's frames (default frames follow it)
  ~frame_id        <prefix>robotiq_ft_frame_id ; header.frame_id, the sensor frame
  ~gravity_frame   <prefix>base_link ; gravity points along its -z
  ~rate            100 Hz (the real sensor's stream rate)
  ~noise_force     0.1 N, ~noise_torque 0.005 Nm (standard deviations; 0 = none)
  ~payload_mass    0 kg ; ~payload_com [0, 0, 0] m in the sensor frame: a held object
  ~gripper_mounted true ; false: the model has no 2F-140, only ~payload hangs on the sensor
  ~devices_file    config/sim_devices.yaml (mass model of the gripper)
  ~max_pose_age    0.5 s ; a pose older than this is stale (robot_state_publisher
                   stopped?): no wrench is published until it is fresh again

Until the pose is known the node waits, warns once and publishes nothing; it
never publishes a wrench for a pose it does not know.
"""

import dataclasses
import threading

import numpy as np

from ur3_ft_gripper_description import kinematics, sim_params, wrench_model


@dataclasses.dataclass
class FT300Settings(object):
    frame_id: str
    gravity_frame: str
    rate: float
    noise_force: float
    noise_torque: float
    payload: wrench_model.Payload
    max_pose_age: float

    @classmethod
    def from_params(cls, get_param):
        """Settings from private parameters (``get_param(name, default)``); ParamError if bad."""
        devices_file = sim_params.existing_file(get_param, '~devices_file',
                                                sim_params.default_devices_file())
        try:
            gripper = wrench_model.load_payload(devices_file)
        except (OSError, ValueError) as exc:
            raise sim_params.ParamError('~devices_file: %s' % exc)
        prefix = get_param('~prefix', '')
        if not isinstance(prefix, str):
            raise sim_params.ParamError('~prefix=%r must be a string' % (prefix,))
        mounted = get_param('~gripper_mounted', True)
        if not isinstance(mounted, bool):
            raise sim_params.ParamError('~gripper_mounted=%r must be true or false' % (mounted,))
        if not mounted:
            gripper = dataclasses.replace(gripper, mass=0.0, com=[0.0, 0.0, 0.0])
        object_mass = sim_params.number(get_param, '~payload_mass', 0.0, minimum=0.0)
        object_com = sim_params.vector3(get_param, '~payload_com', [0.0, 0.0, 0.0])
        return cls(
            frame_id=sim_params.frame(get_param, '~frame_id', prefix + gripper.frame_id),
            gravity_frame=sim_params.frame(get_param, '~gravity_frame', prefix + 'base_link'),
            rate=sim_params.number(get_param, '~rate', gripper.rate, strictly_above=0.0),
            noise_force=sim_params.number(get_param, '~noise_force', gripper.noise_force, minimum=0.0),
            noise_torque=sim_params.number(get_param, '~noise_torque', gripper.noise_torque, minimum=0.0),
            payload=gripper.with_object(object_mass, object_com),
            max_pose_age=sim_params.number(get_param, '~max_pose_age', 0.5, strictly_above=0.0))


class SensorModel(object):
    """Reading = gravity wrench of the payload + noise - zero offset (no ROS)."""

    def __init__(self, settings, rng=None):
        self.settings = settings
        self.rng = rng if rng is not None else np.random.default_rng()
        self.zero = wrench_model.ZeroOffset()
        self.last_true = None  # noise-free wrench at the last known pose
        self._lock = threading.Lock()

    def read(self, sensor_orientation):
        """(force, torque) for the sensor's 3x3 orientation in the gravity frame."""
        payload = self.settings.payload
        true = wrench_model.gravity_wrench(sensor_orientation, payload.mass, payload.com)
        noisy = true
        if self.settings.noise_force or self.settings.noise_torque:
            noisy = wrench_model.add_noise(true, self.settings.noise_force,
                                           self.settings.noise_torque, self.rng)
        with self._lock:
            self.last_true = true
            return self.zero.apply(noisy)

    def set_zero(self):
        """Take the current (noise-free) reading as the new zero; False if no pose is known yet.

        The real sensor averages over its samples when zeroing; the noise-free
        value is what that average converges to.
        """
        with self._lock:
            if self.last_true is None:
                return False
            self.zero.set(self.last_true)
            return True


class PoseWatch(object):
    """Tracks whether the sensor pose is usable, and says so once per change.

    States: 'waiting' (never had a pose), 'ok', 'stale' (TF stopped updating or
    the lookup started failing). Each transition logs exactly one message.
    The wait at start-up is only reported after `quiet_start` seconds, so a
    normal bring-up, where TF arrives within a fraction of a second, is quiet.
    """

    def __init__(self, settings, log_warn, log_info, start_time, quiet_start=1.0):
        self.settings = settings
        self.state = 'waiting'
        self._waiting_said = False
        self._warn, self._info = log_warn, log_info
        self._quiet_until = start_time + quiet_start

    def _enter(self, state, message, log):
        if state != self.state:
            self.state = state
            log(message)

    def fresh(self, transform_stamp, now):
        """True if a transform stamped `transform_stamp` (s; 0 = static) may be used at `now` (s)."""
        age = now - transform_stamp
        if transform_stamp > 0.0 and age > self.settings.max_pose_age:
            self._enter('stale', 'ft300_sim: the pose of %s in %s is %.2f s old (limit ~max_pose_age='
                        '%g s): is robot_state_publisher running? No wrench is published until '
                        'it updates.' % (self.settings.frame_id, self.settings.gravity_frame, age,
                                         self.settings.max_pose_age), self._warn)
            return False
        self._enter('ok', 'ft300_sim: pose of %s in %s known; publishing robotiq_ft_wrench at %g Hz'
                    % (self.settings.frame_id, self.settings.gravity_frame, self.settings.rate),
                    self._info)
        return True

    def missing(self, reason, now):
        """The lookup failed at `now` (s) for `reason`."""
        if self.state == 'waiting':
            if not self._waiting_said and now >= self._quiet_until:
                self._waiting_said = True
                self._warn('ft300_sim: waiting for TF %s -> %s (%s); publishing starts as soon as '
                           'it is available' % (self.settings.gravity_frame,
                                                self.settings.frame_id, reason))
            return
        self._enter('stale', 'ft300_sim: lost TF %s -> %s (%s); no wrench is published until it '
                    'is back' % (self.settings.gravity_frame, self.settings.frame_id, reason),
                    self._warn)


def run(rospy):
    """The node: parameters, publisher, service, loop. Returns the exit status."""
    import tf2_ros
    from geometry_msgs.msg import WrenchStamped
    from std_srvs.srv import Trigger, TriggerResponse

    try:
        settings = FT300Settings.from_params(rospy.get_param)
    except sim_params.ParamError as exc:
        rospy.logfatal('ft300_sim: bad parameter %s', exc)
        return 1
    sensor = SensorModel(settings)
    watch = PoseWatch(settings, rospy.logwarn, rospy.loginfo, rospy.Time.now().to_sec())
    tf_buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(tf_buffer)
    publisher = rospy.Publisher('robotiq_ft_wrench', WrenchStamped, queue_size=10)

    def zero(_request):
        if sensor.set_zero():
            return TriggerResponse(success=True, message='zeroed: later readings are relative '
                                   'to the current one')
        return TriggerResponse(success=False, message='no pose known yet (TF %s -> %s): nothing '
                               'to zero' % (settings.gravity_frame, settings.frame_id))

    rospy.Service('robotiq_ft_zero', Trigger, zero)
    rate = rospy.Rate(settings.rate)
    while not rospy.is_shutdown():
        now = rospy.Time.now()
        try:
            stamped = tf_buffer.lookup_transform(settings.gravity_frame, settings.frame_id,
                                                 rospy.Time(0))
        except tf2_ros.TransformException as exc:
            watch.missing(str(exc).strip() or type(exc).__name__, now.to_sec())
        else:
            if watch.fresh(stamped.header.stamp.to_sec(), now.to_sec()):
                rotation = kinematics.transform_msg_matrix(stamped.transform)[:3, :3]
                force, torque = sensor.read(rotation)
                message = WrenchStamped()
                message.header.stamp = now
                message.header.frame_id = settings.frame_id
                w = message.wrench
                w.force.x, w.force.y, w.force.z = (float(v) for v in force)
                w.torque.x, w.torque.y, w.torque.z = (float(v) for v in torque)
                publisher.publish(message)
        try:
            rate.sleep()
        except rospy.ROSTimeMovedBackwardsException:
            tf_buffer.clear()
        except rospy.ROSInterruptException:
            break
    return 0


def main():
    import rospy
    rospy.init_node('ft300_sim')
    return run(rospy)
