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
import math
import threading

import numpy as np

from ur3_ft_gripper_description import node_loop, sim_params, wrench_model


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
        gripper = sim_params.from_devices_file(get_param, wrench_model.load_payload)
        prefix = sim_params.prefix(get_param)
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


# Noise is drawn for this many readings at once: a numpy call per reading
# cost more than the rest of the reading.
NOISE_BLOCK = 256


class SensorModel(object):
    """Reading = gravity wrench of the payload + noise - zero offset (no ROS).

    The node calls this 100 to 1000 times a second, so the arithmetic is done
    on plain floats: numpy costs more in call overhead than it saves on
    3-vectors (cProfile: half of the node's loop time went to np.cross,
    np.linalg.norm and np.eye). wrench_model.gravity_wrench is the reference
    it is tested against.
    """

    def __init__(self, settings, rng=None):
        self.settings = settings
        self.rng = rng if rng is not None else np.random.default_rng()
        self.zero = wrench_model.ZeroOffset()
        self.last_true = None  # noise-free wrench at the last known pose
        self._lock = threading.Lock()
        payload = settings.payload
        self._weight = float(payload.mass) * wrench_model.STANDARD_GRAVITY
        self._com = tuple(float(v) for v in payload.com)
        self._noisy = bool(settings.noise_force or settings.noise_torque)
        self._sigma = np.array([settings.noise_force] * 3 + [settings.noise_torque] * 3)
        self._noise = []  # pre-drawn noise rows: one numpy call per NOISE_BLOCK readings
        self._offset = (0.0,) * 6

    def read(self, sensor_orientation):
        """(force, torque) for the sensor's 3x3 orientation in the gravity frame."""
        r = sensor_orientation
        # Gravity (world -z) in the sensor frame is R.T @ (0, 0, -1): minus R's last row.
        return self.read_gravity(-float(r[2][0]), -float(r[2][1]), -float(r[2][2]))

    def read_quaternion(self, x, y, z, w):
        """Like read(), for the sensor's orientation as a unit quaternion (a tf2 lookup's)."""
        # Last row of kinematics.quaternion_matrix(x, y, z, w), negated.
        return self.read_gravity(2.0 * (y * w - x * z), -2.0 * (y * z + x * w),
                                 2.0 * (x * x + y * y) - 1.0)

    def read_gravity(self, gx, gy, gz):
        """(force, torque) tuples for gravity along (gx, gy, gz) in the sensor frame (any length)."""
        norm = math.sqrt(gx * gx + gy * gy + gz * gz)
        if not math.isfinite(norm) or norm == 0.0:
            raise ValueError('gravity direction is zero or not finite: %r' % ((gx, gy, gz),))
        scale = self._weight / norm
        fx, fy, fz = scale * gx, scale * gy, scale * gz
        cx, cy, cz = self._com
        true = (fx, fy, fz, cy * fz - cz * fy, cz * fx - cx * fz, cx * fy - cy * fx)
        values = true
        if self._noisy:
            if not self._noise:
                self._noise = (self.rng.standard_normal((NOISE_BLOCK, 6)) * self._sigma).tolist()
            values = [v + n for v, n in zip(true, self._noise.pop())]
        with self._lock:
            self.last_true = true
            offset = self._offset
        reading = [v - o for v, o in zip(values, offset)]
        return tuple(reading[:3]), tuple(reading[3:])

    def set_zero(self):
        """Take the current (noise-free) reading as the new zero; False if no pose is known yet.

        The real sensor averages over its samples when zeroing; the noise-free
        value is what that average converges to.
        """
        with self._lock:
            if self.last_true is None:
                return False
            self.zero.set((self.last_true[:3], self.last_true[3:]))
            self._offset = tuple(self.zero.force.tolist() + self.zero.torque.tolist())
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
        """`message` is a callable: the text is only built on a change, not every cycle."""
        if state != self.state:
            self.state = state
            log(message())

    def fresh(self, transform_stamp, now):
        """True if a transform stamped `transform_stamp` (s; 0 = static) may be used at `now` (s)."""
        age = now - transform_stamp
        if transform_stamp > 0.0 and age > self.settings.max_pose_age:
            self._enter('stale', lambda: (
                'ft300_sim: the pose of %s in %s is %.2f s old (limit ~max_pose_age=%g s): is '
                'robot_state_publisher running? No wrench is published until it updates.'
                % (self.settings.frame_id, self.settings.gravity_frame, age,
                   self.settings.max_pose_age)), self._warn)
            return False
        if self.state != 'ok':
            self._enter('ok', lambda: (
                'ft300_sim: pose of %s in %s known; publishing robotiq_ft_wrench at %g Hz'
                % (self.settings.frame_id, self.settings.gravity_frame, self.settings.rate)),
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
        self._enter('stale', lambda: (
            'ft300_sim: lost TF %s -> %s (%s); no wrench is published until it is back'
            % (self.settings.gravity_frame, self.settings.frame_id, reason)), self._warn)


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
    latest = rospy.Time(0)
    # One message, refilled each cycle: publish() serializes it before returning.
    message = WrenchStamped()
    message.header.frame_id = settings.frame_id
    force_msg, torque_msg = message.wrench.force, message.wrench.torque

    def step():
        now = rospy.Time.now()
        try:
            # lookup_transform() without a timeout is can_transform() + this call.
            stamped = tf_buffer.lookup_transform_core(settings.gravity_frame, settings.frame_id,
                                                      latest)
        except tf2_ros.TransformException as exc:
            watch.missing(str(exc).strip() or type(exc).__name__, now.to_sec())
            return
        if watch.fresh(stamped.header.stamp.to_sec(), now.to_sec()):
            q = stamped.transform.rotation
            force, torque = sensor.read_quaternion(q.x, q.y, q.z, q.w)
            message.header.stamp = now
            force_msg.x, force_msg.y, force_msg.z = force
            torque_msg.x, torque_msg.y, torque_msg.z = torque
            publisher.publish(message)

    return node_loop.run_at_rate(rospy, settings.rate, step, on_time_jump=tf_buffer.clear)


def main():
    import rospy
    rospy.init_node('ft300_sim')
    return run(rospy)
