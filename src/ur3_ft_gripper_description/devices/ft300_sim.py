"""Simulated Robotiq FT 300 behind the interface of Robotiq's own driver (rq_sensor).

Like robotiq_ft_sensor's ``rq_sensor`` (node name ``robotiq_ft_sensor``) it
publishes, at the sensor's 100 Hz, ``robotiq_ft_sensor``
(robotiq_ft_sensor/ft_sensor) and ``robotiq_ft_wrench``
(geometry_msgs/WrenchStamped in ``~frame_id``) with the same values, in the
device's resolution (its stream carries 16-bit counts of 0.01 N and
0.001 Nm, which rq_sensor turns into float32), and serves
``robotiq_ft_sensor_acc`` (robotiq_ft_sensor/sensor_accessor) with
rq_sensor's answers (``accessor_reply``).

The reading is what the real sensor shows when nothing touches the tool:
the weight of the gripper (and of a held object) for the current pose,
taken from TF, plus the unit's own offset (~unit_offset: a real unit's by
default, so code that forgets SET_ZERO reads nonsense, as on the robot), plus
white noise, minus the zero that SET_ZERO takes. The
gripper's mass and centre of mass are the model's own: the inertials of
every link below ``~frame_id`` in ``robot_description`` (fingers open;
looked for up the namespaces, like ``rospy.search_param``).

Its private parameters are declared in PARAMETERS below (their reference:
doc/node_parameters.md). ``~serial_id`` and ``~max_retries`` are rq_sensor's:
accepted, as a launch file for the real sensor sets them, and unused.

Until the pose is known the node waits, warns once and publishes nothing; it
never publishes a wrench for a pose it does not know.

With ``~physics`` true (sim_devices.launch physics:=true) the true wrench is
the physics cell's instead (MuJoCo's force and torque at the sensor frame:
the tool side's weight and inertia, contacts, whatever the fingers hold),
read through the private link from the arm's node (physics/link.py); SET_ZERO,
the noise and the stream's resolution stay as above. TF and ~payload_mass /
~payload_com are not used then: physics weighs what the gripper holds. On
simulated time (use_sim_time) the cell keeps one sample per period of its
time for this node, so the stream carries exactly ~rate readings per
simulated second, each stamped with its time, however late the node runs.

With ``~modbus_rtu_port`` (a path) the sensor is also on its serial line, as
behind its USB adapter, on a pseudo-terminal linked at that path
(network/ft300_wire.py): Modbus RTU and the data stream, which rq_sensor and
Modbus clients read. They carry the device's own readings, one for each this
node publishes: rq_sensor zeroes in the driver, so they keep the unit's offset.

Both sources, the gravity model and the cell, sit behind one seam
(GravitySource, CellSource: ``readings(now)``) and one publishing loop.
"""

import dataclasses
import numpy as np

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.devices import node_loop, sim_params, wrench_model
from ur3_ft_gripper_description.devices.physics import link
from ur3_ft_gripper_description.devices.network import listen, modbus_line
from ur3_ft_gripper_description.model import inertials


PARAMETERS = (
    sim_params.PREFIX,
    sim_params.Param('~frame_id', sim_params.StartupDefault('~prefix + the sensor\'s `frame_id` in ~devices_file'),
                     'header.frame_id of the readings: the sensor frame', sim_params.frame),
    sim_params.Param('~gravity_frame', sim_params.StartupDefault('~prefix + `base_link`'),
                     'Gravity points along its -z', sim_params.frame),
    sim_params.Param('~rate', sim_params.StartupDefault('the sensor\'s `rate` in ~devices_file (its stream rate)'),
                     'Publishing rate (Hz)', sim_params.number(strictly_above=0.0)),
    sim_params.Param('~noise_force', sim_params.StartupDefault('the sensor\'s `noise_force` in ~devices_file'),
                     'Standard deviation of the force noise (N); 0: none', sim_params.number(minimum=0.0)),
    sim_params.Param('~noise_torque', sim_params.StartupDefault('the sensor\'s `noise_torque` in ~devices_file'),
                     'Standard deviation of the torque noise (Nm); 0: none', sim_params.number(minimum=0.0)),
    sim_params.Param('~unit_offset', sim_params.StartupDefault('the sensor\'s `unit_offset` in ~devices_file'),
                     'What the unit reads before SET_ZERO beside its load (fx fy fz N, tx ty tz N m), a list or a '
                     'string like "0 0 0 0 0 0": on the serial line always, on the topics until SET_ZERO',
                     sim_params.wrench),
    sim_params.Param('~payload_mass', 0.0, 'Mass of a held object (kg), added to what the model hangs below the '
                     'sensor; not with ~physics, which weighs what the gripper holds', sim_params.number(minimum=0.0)),
    sim_params.Param('~payload_com', [0.0, 0.0, 0.0], 'Centre of mass of the held object (m, x y z in the sensor '
                     'frame), a list or a string like "0 0 0.1"', sim_params.vector3),
    sim_params.DEVICES_FILE,
    sim_params.Param('~max_pose_age', 0.5, 'A sensor pose older than this (s) is stale (robot_state_publisher '
                     'stopped?): nothing is published until it is fresh again', sim_params.number(strictly_above=0.0)),
    sim_params.PHYSICS,
    sim_params.Param('~modbus_rtu_port', '', 'Path of a serial port where the sensor also answers as on its USB '
                     'adapter (Modbus RTU, slave 9, 19200 8N1, then its data stream; '
                     'config/robotiq_ft300_modbus.yaml): a symbolic link made there to a pseudo-terminal, for '
                     'rq_sensor (its ~serial_id: the pts/N the node logs) or any client; empty: none'),
    sim_params.Param('~serial_id', '', "rq_sensor's serial device: accepted, unused (said once if set)"),
    sim_params.Param('~max_retries', 100, "rq_sensor's reconnection tries: accepted, unused"),
)


@dataclasses.dataclass
class FT300Settings(object):
    frame_id: str
    gravity_frame: str
    rate: float
    noise_force: float
    noise_torque: float
    unit_offset: tuple
    load: wrench_model.Load
    identity: dict
    max_pose_age: float

    @classmethod
    def from_params(cls, get_param):
        """Settings from private parameters (``get_param(name, default)``); ParamError if bad."""
        def param(name, **default):
            return sim_params.read(get_param, PARAMETERS, name, **default)
        sensor = sim_params.from_devices_file(get_param, PARAMETERS, wrench_model.load_sensor_spec)
        prefix = param('~prefix')
        frame_id = param('~frame_id', default=prefix + sensor.frame_id)
        below_sensor = wrench_model.Load(*tool_side_load(get_param('robot_description', None), frame_id))
        object_mass = param('~payload_mass')
        object_com = param('~payload_com')
        return cls(
            frame_id=frame_id,
            gravity_frame=param('~gravity_frame', default=prefix + 'base_link'),
            rate=param('~rate', default=sensor.rate),
            noise_force=param('~noise_force', default=sensor.noise_force),
            noise_torque=param('~noise_torque', default=sensor.noise_torque),
            unit_offset=tuple(param('~unit_offset', default=sensor.unit_offset)),
            load=below_sensor.with_object(object_mass, object_com),
            identity=sensor.identity,
            max_pose_age=param('~max_pose_age'))


def tool_side_load(description, frame_id):
    """(mass, com in frame_id) of the model's links below the sensor frame; ParamError if it cannot."""
    fix = 'load the model first (load_ur_ft_gripper.launch sets robot_description)'
    if not isinstance(description, str) or not description.strip():
        raise sim_params.ParamError('robot_description is not set: %s' % fix)
    try:
        return inertials.mass_below(kinematics.Model(description), frame_id)
    except ValueError as exc:
        raise sim_params.ParamError('robot_description: %s; give ~frame_id or ~prefix for the model, or %s'
                                    % (exc, fix))
    except Exception as exc:  # urdf_parser_py raises many types on a malformed model
        raise sim_params.ParamError('robot_description is not a URDF this node can read (%s): %s' % (
            ' '.join(str(exc).split()) or type(exc).__name__, fix))


def _searching_get_param(rospy):
    """rospy.get_param, but robot_description is looked for up the namespaces (rospy.search_param).

    A sensor started in a namespace of its own still finds the model loaded
    beside the robot, as robot_state_publisher's users expect.
    """
    def get_param(name, default=None):
        if name == 'robot_description':
            name = rospy.search_param(name) or name
        return rospy.get_param(name, default)
    return get_param


# Noise is drawn for this many readings at once: a numpy call per reading
# cost more than the rest of the reading.
NOISE_BLOCK = 256
# On the simulated clock the noise of each reading is fixed by its time: blocks of it drawn from
# generators seeded by (this, the block's number), so a run repeats exactly.
NOISE_SEED = 300

# The stream's resolution (rq_sensor_com.cpp divides its 16-bit counts by 100
# for forces and by 1000 for torques).
FORCE_RESOLUTION, TORQUE_RESOLUTION = 0.01, 0.001
COUNT_MIN, COUNT_MAX = -32768, 32767


def device_counts(values):
    """(fx, fy, fz, tx, ty, tz) in the stream's 16-bit counts."""
    return [min(max(round(v / r), COUNT_MIN), COUNT_MAX) for v, r in
            zip(values, (FORCE_RESOLUTION,) * 3 + (TORQUE_RESOLUTION,) * 3)]


def from_counts(counts):
    """Counts as the float32 values rq_sensor publishes."""
    scaled = [c / 100.0 for c in counts[:3]] + [c / 1000.0 for c in counts[3:]]
    return tuple(np.array(scaled, dtype=np.float32).tolist())


def as_device_sends(values):
    """(fx, fy, fz, tx, ty, tz) rounded to the stream's counts, as the float32 rq_sensor publishes."""
    return from_counts(device_counts(values))


class SensorModel(object):
    """The device's reading = true wrench + the unit's offset + noise; the driver's = that - the zero (no ROS).

    Both in the stream's resolution. rq_sensor zeroes in the driver: SET_ZERO takes the device's reading
    of the moment as the zero, and the device itself (its registers, its stream) goes on sending its own
    reading, offset included.

    The true wrench comes from one of two sources: the gravity of the modelled
    load for the sensor's orientation (read_quaternion, read_gravity), or a
    physics cell's reading (read).
    """

    def __init__(self, settings, rng=None):
        self.settings = settings
        self.rng = rng if rng is not None else np.random.default_rng()
        self.last_true = None  # noise-free wrench at the last known pose
        self._zero_requested = False
        self._zero_index = None  # the reading number on the simulated clock a zero was requested at
        self._mass = float(settings.load.mass)
        self._com = tuple(float(v) for v in settings.load.com)
        self._noisy = bool(settings.noise_force or settings.noise_torque)
        self._sigma = np.array([settings.noise_force] * 3 + [settings.noise_torque] * 3)
        self._noise = []  # pre-drawn noise rows: one numpy call per NOISE_BLOCK readings
        self._indexed_block, self._indexed_noise = None, None  # the same, by reading number
        self._unit_offset = tuple(float(v) for v in settings.unit_offset)
        self._zero = [0] * 6  # the driver's zero, in counts: a reading of the device's
        self._device = [0] * 6  # the device's own last reading (counts), before the driver's zero

    def read_quaternion(self, x, y, z, w):
        """The reading for the sensor's orientation as a unit quaternion (a tf2 lookup's)."""
        return self.read(self.true_for_quaternion(x, y, z, w))

    def read_gravity(self, gx, gy, gz):
        """(fx, fy, fz, tx, ty, tz), as the device sends it, for gravity along (gx, gy, gz)."""
        return self.read(wrench_model.gravity_wrench(gx, gy, gz, self._mass, self._com))

    def true_for_quaternion(self, x, y, z, w):
        """The noise-free wrench of the modelled load for the sensor's orientation (a unit quaternion)."""
        return wrench_model.gravity_wrench(*wrench_model.gravity_direction(x, y, z, w), mass=self._mass,
                                           com=self._com)

    def read(self, true, index=None):
        """(fx, fy, fz, tx, ty, tz), as the device sends it, for the true wrench `true` (six floats).

        `index`: the reading's number on the simulated clock (its stamp over the period), which picks
        its noise: the same simulated time gets the same noise in every run, however the processes
        were scheduled. None: the next of this sensor's own noise sequence (the wall clock).
        """
        if self._zero_requested and (index is None or self._zero_index is None or index >= self._zero_index):
            # As rq_sensor_com does: the reading before the request becomes the zero.
            # Its noise-free value is taken, what the noise averages out to.
            self._zero_requested = False
            held = self.last_true if self.last_true is not None else true
            self._zero = device_counts([v + o for v, o in zip(held, self._unit_offset)])
        self.last_true = true
        values = [v + o for v, o in zip(true, self._unit_offset)]
        if self._noisy:
            if index is None:
                if not self._noise:
                    self._noise = (self.rng.standard_normal((NOISE_BLOCK, 6)) * self._sigma).tolist()
                row = self._noise.pop()
            else:
                row = self._noise_at(int(index))
            values = [v + n for v, n in zip(values, row)]
        # As rq_sensor subtracts its zero from each reading: both are the device's, in its resolution.
        self._device = device_counts(values)
        return from_counts([d - z for d, z in zip(self._device, self._zero)])

    def device_reading(self):
        """The device's own last reading, as its registers and its stream carry it: no zero, the unit's offset."""
        return from_counts(self._device)

    def _noise_at(self, index):
        """The noise row of reading `index`: block index // NOISE_BLOCK drawn from a generator seeded by it."""
        block = index // NOISE_BLOCK
        if self._indexed_block != block:
            rng = np.random.default_rng((NOISE_SEED, block))
            self._indexed_noise = (rng.standard_normal((NOISE_BLOCK, 6)) * self._sigma).tolist()
            self._indexed_block = block
        return self._indexed_noise[index % NOISE_BLOCK]

    def request_zero(self, index=None):
        """SET_ZERO: the next reading and those after it are relative to the current one.

        `index`: the request's reading number on the simulated clock. Readings before it that this node
        has yet to send (it reads a physics cell's samples in order, and on a busy machine runs behind)
        are not zeroed, and the one just before it becomes the zero, as the real sensor's reading at the
        request does.
        """
        self._zero_requested = True
        self._zero_index = index


def accessor_reply(command_id, command, sensor, identity, log, zero_index=None):
    """(success, res) of rq_sensor's robotiq_ft_sensor_acc for a request; `log` has info/warn/warn_once.

    The deprecated 7-character string (``command``) wins over ``command_id``,
    and never reports success, as in rq_sensor.cpp. Where rq_sensor answers
    with a buffer it never wrote (a string that is not 7 characters, an
    unknown name), this answers ''.
    """
    if command:
        log.warn_once('Usage of command-string is deprecated, please use the numeric command_id')
        log.info('I heard: [%s]' % command)
        res = ''
        if len(command) == 7:
            action, name = command[:3], command[4:]
            if action == 'GET':
                res = {'SNU': identity['serial_number'], 'FWV': identity['firmware_version'],
                       'PYE': identity['production_year']}.get(name, '')
            elif action == 'SET' and 'ZRO' in name:
                sensor.request_zero(zero_index)
                res = 'Done'
        log.info('I send: [%s]' % res)
        return False, res
    if command_id == 1:
        return True, identity['serial_number']
    if command_id == 2:
        return True, identity['firmware_version']
    if command_id == 4:
        return True, identity['production_year']
    if command_id == 8:
        sensor.request_zero(zero_index)
        return True, 'Done'
    log.warn("Unsupported command_id '%i', should be in [1, 2, 4, 8]" % command_id)
    return False, 'Unsupported command_id'


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
                'ft300_sim: pose of %s in %s known; publishing robotiq_ft_sensor and robotiq_ft_wrench at %g Hz'
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


class _Log(object):
    """rospy's loggers as accessor_reply takes them."""

    def __init__(self, rospy):
        self.info, self.warn = rospy.loginfo, rospy.logwarn
        self._once = set()

    def warn_once(self, text):
        if text not in self._once:
            self._once.add(text)
            self.warn(text)


class GravitySource(object):
    """The true wrench of the kinematic simulation: the modelled load's weight for the sensor's pose in TF.

    `readings(now)`: [(stamp, true wrench, acceleration)], one for the pose at `now` (rospy.Time), or none
    while the pose is unknown or stale (PoseWatch says so). The acceleration (g, sensor frame) is what the
    sensor's accelerometer reads held still: gravity's reaction. The kinematic arm's own accelerations are
    not in it (the physics cell's reading has them).
    """

    def __init__(self, rospy, settings, sensor):
        import tf2_ros
        self.tf2_ros, self.settings, self.sensor = tf2_ros, settings, sensor
        self.watch = PoseWatch(settings, rospy.logwarn, rospy.loginfo, rospy.Time.now().to_sec())
        self.buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(self.buffer)
        self._latest = rospy.Time(0)

    def readings(self, now):
        try:
            # lookup_transform() without a timeout is can_transform() + this call.
            stamped = self.buffer.lookup_transform_core(self.settings.gravity_frame, self.settings.frame_id,
                                                        self._latest)
        except self.tf2_ros.TransformException as exc:
            self.watch.missing(str(exc).strip() or type(exc).__name__, now.to_sec())
            return ()
        if not self.watch.fresh(stamped.header.stamp.to_sec(), now.to_sec()):
            return ()
        q = stamped.transform.rotation
        gx, gy, gz = wrench_model.gravity_direction(q.x, q.y, q.z, q.w)
        return ((now, self.sensor.true_for_quaternion(q.x, q.y, q.z, q.w), (-gx, -gy, -gz)),)

    def restart(self):
        """ROS time jumped back: what TF held is of another time."""
        self.buffer.clear()


class CellSource(object):
    """The true wrench of the physics cell, through the link (`client`: a link.CellClient).

    On simulated time the cell keeps one sample per `period` s of its time for this node, so the
    stream has every reading, stamped with its simulated time, however late this node runs. On the
    wall clock (use_sim_time false) each reading is the cell's wrench when asked, stamped now.
    """

    def __init__(self, rospy, client, period, sim_time):
        self.rospy, self.client, self.period, self.sim_time = rospy, client, period, sim_time
        self._dropped_said = False
        if sim_time:
            client.wrench_samples(period)  # the cell keeps samples from here on

    def readings(self, now):
        """[(stamp, true wrench, acceleration in g)], as GravitySource's, from the cell's samples."""
        if not self.sim_time:
            wrench, specific_force = self.client.wrench()[1:]
            return ((now, wrench, _in_g(specific_force)),)
        samples, dropped = self.client.wrench_samples(self.period)[1:]
        if dropped and not self._dropped_said:
            self._dropped_said = True
            self.rospy.logwarn('ft300_sim: %d readings were lost: this node fell more than the cell keeps '
                               'behind the physics cell; the machine is too busy for this real-time factor'
                               % dropped)
        Time = self.rospy.Time
        return [(Time(*divmod(int(round(t * 1e9)), 1000000000)), wrench, _in_g(specific_force))
                for t, wrench, specific_force in samples]

    def restart(self):
        pass


def _in_g(specific_force):
    """An accelerometer's reading (m/s^2) in standard gravities, as the FT 300's registers give it."""
    return tuple(a / wrench_model.STANDARD_GRAVITY for a in specific_force)


def run(rospy):
    """The node: parameters, the true wrench's source, publishers, service, one publishing loop.

    Returns the exit status.
    """
    from geometry_msgs.msg import WrenchStamped
    from robotiq_ft_sensor.msg import ft_sensor
    from robotiq_ft_sensor.srv import sensor_accessor, sensor_accessorResponse

    try:
        settings = FT300Settings.from_params(_searching_get_param(rospy))
    except sim_params.ParamError as exc:
        rospy.logfatal('ft300_sim: bad parameter %s', exc)
        return 1
    physics = sim_params.read(rospy.get_param, PARAMETERS, '~physics')
    if physics and sim_params.read(rospy.get_param, PARAMETERS, '~payload_mass'):
        rospy.logwarn('ft300_sim: ~payload_mass is not used with ~physics: the sensor weighs what the gripper holds')
    # Read as rq_sensor reads them; there is no serial device to open or retry.
    serial_id = sim_params.read(rospy.get_param, PARAMETERS, '~serial_id')
    sim_params.read(rospy.get_param, PARAMETERS, '~max_retries')
    if serial_id:
        rospy.loginfo('ft300_sim: ~serial_id %s is not used: this sensor is simulated', serial_id)
    sensor = SensorModel(settings)
    sim_time = bool(rospy.get_param('/use_sim_time', False))
    if physics:
        source = _cell_source(rospy, settings, sim_time)
        if not isinstance(source, CellSource):
            return source
    else:
        source = GravitySource(rospy, settings, sensor)
    try:
        wire = start_serial_line(rospy.get_param, settings.identity, rospy.logwarn)
    except (listen.ListenError, ValueError, modbus_line.ModbusUnavailable) as exc:
        rospy.logfatal('ft300_sim: %s', exc)
        return 1
    if wire is not None:
        rospy.on_shutdown(wire[1].shutdown)
        rospy.loginfo("ft300_sim: the FT 300 answers on its serial line at %s (%s): for rq_sensor, the real "
                      "bring-up's ft_serial_id:=%s", wire[1].link, wire[1].path, wire[1].path[len('/dev/'):])
    sensor_publisher = rospy.Publisher('robotiq_ft_sensor', ft_sensor, queue_size=512)
    wrench_publisher = rospy.Publisher('robotiq_ft_wrench', WrenchStamped, queue_size=512)
    log = _Log(rospy)

    period_ns = int(round(1e9 / settings.rate))

    def accessor(request):
        now = rospy.Time.now().to_nsec() // period_ns if sim_time else None
        success, res = accessor_reply(request.command_id, request.command, sensor,
                                      settings.identity, log, zero_index=now)
        return sensor_accessorResponse(success=success, res=res)

    rospy.Service('robotiq_ft_sensor_acc', sensor_accessor, accessor)
    # One message each, refilled for every reading: publish() serializes before returning.
    stream = ft_sensor()
    message = WrenchStamped()
    message.header.frame_id = settings.frame_id
    force_msg, torque_msg = message.wrench.force, message.wrench.torque
    lost = []

    def step(now):
        try:
            readings = source.readings(now)
        except link.LinkError as exc:
            lost.append(link.lost_cell(rospy, 'ft300_sim', exc))
            return
        for stamp, true, acceleration in readings:
            fx, fy, fz, tx, ty, tz = sensor.read(true, stamp.to_nsec() // period_ns if sim_time else None)
            stream.Fx, stream.Fy, stream.Fz, stream.Mx, stream.My, stream.Mz = fx, fy, fz, tx, ty, tz
            sensor_publisher.publish(stream)
            message.header.stamp = stamp
            force_msg.x, force_msg.y, force_msg.z = fx, fy, fz
            torque_msg.x, torque_msg.y, torque_msg.z = tx, ty, tz
            wrench_publisher.publish(message)
            if wire is not None:
                wire[0].reading(sensor.device_reading(), acceleration)

    # One reading per period, stamped with it, however late this node runs: the unit streams from its own
    # clock. On the wall clock a backlog of more than a second (the machine slept) is dropped.
    status = node_loop.run_on_every_tick(rospy, settings.rate, step, on_time_jump=source.restart,
                                         max_backlog=None if sim_time else int(settings.rate))
    return 1 if lost else status


def start_serial_line(get_param, identity, log):
    """(ft300_wire.Ft300Line, its PseudoTerminal) when ~modbus_rtu_port names a path, else None; listen.ListenError,
    ValueError or modbus_line.ModbusUnavailable (one line each) when it cannot start."""
    path = sim_params.read(get_param, PARAMETERS, '~modbus_rtu_port')
    if not path:
        return None
    from ur3_ft_gripper_description.devices.network import ft300_wire
    return ft300_wire.serve(ft300_wire.read_table(), identity, log, link=path)


def _cell_source(rospy, settings, sim_time):
    """The CellSource of the physics cell beside this node, or the exit status when there is none to read."""
    client = link.wait_for_cell(rospy, 'ft300_sim')
    if client is None:
        return 0
    if client.info['ft_frame'] != settings.frame_id:
        rospy.logfatal('ft300_sim: the physics cell has %s where this sensor reads %s: give both the same '
                       'model and ~prefix (or ~frame_id)', client.info['ft_frame'] or 'no FT 300', settings.frame_id)
        return 1
    period = 1.0 / settings.rate
    try:
        source = CellSource(rospy, client, period, sim_time)
    except link.LinkError as exc:
        rospy.logfatal('ft300_sim: ~rate=%g Hz: %s' % (settings.rate, exc))
        return 1
    rospy.loginfo('ft300_sim: reading %s from the physics cell; publishing robotiq_ft_sensor and '
                  'robotiq_ft_wrench at %g Hz of %s time', settings.frame_id, settings.rate,
                  'simulated' if sim_time else 'wall-clock')
    return source


def main():
    return node_loop.main('robotiq_ft_sensor', run)
