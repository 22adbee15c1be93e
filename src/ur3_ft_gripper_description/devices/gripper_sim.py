"""Simulated Robotiq 2F-140 behind the register interface of Robotiq's own driver.

The real drivers (robotiq_2f_gripper_control's Robotiq2FGripperRtuNode.py and
Robotiq2FGripperTcpNode.py, node name ``robotiq2FGripper``) subscribe
``Robotiq2FGripperRobotOutput`` (Robotiq2FGripper_robot_output: rACT rGTO
rATR rPR rSP rFR) and publish ``Robotiq2FGripperRobotInput``
(Robotiq2FGripper_robot_input: gACT gGTO gSTA gOBJ gFLT gPR gPO gCU). This
node does the same, with the registers behaving as the 2F-85 & 2F-140
Instruction Manual (section 4, "Control") describes them:

* rACT 0 -> 1 starts the activation: gACT 1, gSTA 1 for ``activation_time``,
  then gSTA 3. rACT 0 resets the gripper and clears faults (all status 0).
* Before the activation is complete a motion request (rGTO 1) does nothing:
  gFLT 0x07 while rACT is 0 ("the activation bit must be set prior to
  action"), 0x05 while activating ("action delayed"; it runs afterwards).
* rGTO 1 moves toward rPR (0 open .. 255 closed, within the unit's
  ``gpo_open`` .. ``gpo_closed``) at the speed rSP selects (min_speed ..
  max_speed); rGTO 0 stops the fingers where they are. gGTO echoes rGTO,
  gPR echoes rPR, gPO is the actual position, gCU a plausible current
  (moving, or holding with a force from rFR; see config/sim_devices.yaml).
* gOBJ: 0 while moving, 2 when closing stopped on an object (1 when opening
  did), 3 at the requested position (also once a held object is lost). An
  object stays detected until the next motion request, or until the fingers
  travel OBJECT_LOST_TRAVEL on towards the request: the object slipped out
  (the manual's gOBJ 3 is "object lost or dropped"). The manual says to
  ignore gOBJ while gGTO is 0; after a stop it reads 3 here, so that a
  client waiting for the fingers to stop sees it.
* rATR 1 (with rACT 1) starts the automatic release: it overrides every
  other request, opens slowly (min_speed) to the mechanical end (gPO 0) with
  gFLT 0x0B, then reports gFLT 0x0F and moves no more until a reset (rACT 0).
* rACT, rGTO and rATR are bits; a larger value is taken as 1, which is what
  Robotiq's driver sends to the device for it (baseRobotiq2FGripper's
  verifyCommand clamps each to 0..1), with one warning per register and
  RATE_LIMIT seconds.

The fingers themselves move behind one seam, so that the register machine
above is the same for both:

* KinematicFingers (the default): straight toward the request at the speed
  asked for; an object is a width, ``~object_width`` (m between the pads;
  unset: none), on which closing stops;
* PhysicsFingers (``~physics`` true): the physics cell's fingers, through the
  private link to the arm's node (physics/link.py). rPR becomes a pad gap
  through the unit's register scale (config/sim_devices.yaml), which the
  finger drive approaches at rSP's speed, squeezing with at most rFR's force,
  linear over the 2F-140's 10 to 125 N (config/physics.yaml: the manual gives
  the range, not the law; linear is assumed); the model's own finger
  kinematics (GripperKinematics) turn the gap into finger_joint. gPO is the
  measured gap through the register scale, and the request once the fingers
  stand at it: so a gap the model's pads cannot open (their last 11.5 mm)
  reads as the request, as the kinematic fingers do. gOBJ comes from the
  fingers stopping short of the request on an object, gCU follows the drive's
  force (max_grip_current at 125 N).

With ``~urcap_address`` (the simulated robot's address), the registers are also
served as Robotiq's gripper URCap serves them on the robot: SET and GET on a TCP
socket (network/robotiq_urcap.py, port 63352), one register machine behind both.
With ``~modbus_rtu_port`` (a path) they are served on Modbus RTU as the gripper
serves them on its RS-485 line, on a pseudo-terminal linked at that path, and
with ``~modbus_tcp_address`` on Modbus TCP as Robotiq's gateway serves them
(network/robotiq_modbus.py): Robotiq's own Modbus nodes and any Modbus client
drive the same register machine.

Its private parameters are declared in PARAMETERS below (their reference:
doc/node_parameters.md).
"""

import collections
import math
import threading
import time

from ur3_ft_gripper_description.devices import gripper_model, node_loop, sim_params
from ur3_ft_gripper_description.devices.physics import link
from ur3_ft_gripper_description.devices.network import listen, modbus_line, robotiq_modbus, robotiq_urcap

# A kind of nonsense register value is warned about at most once per this many seconds.
RATE_LIMIT = 10.0
# Fingers that stopped on an object and then travel this far (m) on towards the request have lost it.
# Not published: the simulation's choice, beyond what the physics pads move on a held part (the pads
# sink up to 2 mm into it as they squeeze; a can rocking in them moves them 0.5 mm).
OBJECT_LOST_TRAVEL = 0.003

FAULT_NONE = 0x00
FAULT_ACTION_DELAYED = 0x05       # activation must be completed prior to action
FAULT_ACTIVATION_BIT = 0x07       # the activation bit must be set prior to action
FAULT_AUTO_RELEASE_ACTIVE = 0x0B  # automatic release in progress
FAULT_AUTO_RELEASE_DONE = 0x0F    # automatic release completed

STATUS_FIELDS = ('gACT', 'gGTO', 'gSTA', 'gOBJ', 'gFLT', 'gPR', 'gPO', 'gCU')
COMMAND_FIELDS = ('rACT', 'rGTO', 'rATR', 'rPR', 'rSP', 'rFR')
BITS = ('rACT', 'rGTO', 'rATR')


class GripperSpec(object):
    """The device figures of the ``gripper`` section of config/sim_devices.yaml."""

    KEYS = ('stroke', 'min_speed', 'max_speed', 'gpo_open', 'gpo_closed', 'activation_time',
            'moving_current', 'max_grip_current')

    def __init__(self, spec):
        for key in self.KEYS:
            setattr(self, key, float(spec[key]))
        self.scale = gripper_model.RegisterScale(self.stroke, self.gpo_open, self.gpo_closed)

    def speed_counts(self, rsp):
        """Finger speed in position counts per second for speed register `rsp`."""
        metres = self.min_speed + (self.max_speed - self.min_speed) * rsp / 255.0
        return metres * self.scale.counts_per_metre


# Two simulated times this close (s) are one: the cell's are whole timesteps, the node's whole periods.
SAME_TIME = 1e-6

# What the fingers are doing, as the seam reports it (the physics cell's own words).
MOVING, AT_TARGET, ON_OBJECT = 'moving', 'at_target', 'on_object'


class KinematicFingers(object):
    """Fingers without physics: straight toward the target, stopping on a part `object_width` m wide when closing.

    The seam, in register counts (gPO's scale): `position`; go(target, speed
    counts/s, force 0..1 of the grip force range); stop(); advance(dt, at=None)
    -> MOVING, AT_TARGET or ON_OBJECT (`at`: the simulated time the status is
    for); squeeze(), the share of the full grip force the fingers press an
    object with.
    """

    def __init__(self, spec, object_width=None, initial_position=None):
        self.object_position = None if object_width is None else spec.scale.position(object_width)
        self.position = float(spec.gpo_open if initial_position is None else initial_position)
        self.target, self.speed, self.force = self.position, 0.0, 0.0
        self.motion = AT_TARGET

    def go(self, target, speed, force):
        if self.motion == ON_OBJECT and target >= self.position:
            self.force = force
            return  # still squeezing the part
        self.target, self.speed, self.force = float(target), float(speed), float(force)
        self.motion = MOVING

    def stop(self):
        if self.motion == MOVING:
            self.target, self.motion = self.position, AT_TARGET

    def advance(self, dt, at=None):
        if self.motion == MOVING:
            start = self.position
            self.position = gripper_model.step_toward(start, self.target, self.speed, dt)
            obj = self.object_position
            if obj is not None and start <= obj < self.position:
                self.position, self.motion = obj, ON_OBJECT
            elif self.position == self.target:
                self.motion = AT_TARGET
        return self.motion

    def squeeze(self):
        return self.force if self.motion == ON_OBJECT else 0.0


class PhysicsFingers(object):
    """The physics cell's fingers through the link (`client`: a link.CellClient), in register counts.

    Same seam as KinematicFingers; gPO is the gap through the unit's register
    scale, or the request while the fingers stand at it. With `sample_period`
    (s, the node's on a simulated clock), advance(dt, at) reports the fingers
    as the cell kept them at simulated time `at`, so that a node running late
    still publishes each status with the fingers of its own time.
    """

    def __init__(self, client, spec, open_tolerance=0.001, sample_period=None):
        self.client, self.scale = client, spec.scale
        self.sample_period, self._waiting, self._commanded_at = sample_period, collections.deque(), -math.inf
        if sample_period is not None:
            self.client.finger_samples(sample_period)  # the cell keeps them from now on
        gripper = client.info['gripper']
        self.force_range = tuple(gripper['grip_force_range'])
        state = client.finger()[1]
        self.speed, self.force = 0.0, self.force_range[0]
        # At the model's open end at start-up the fingers stand as a unit opened fully: at gpo_open.
        wide = state['opening'] >= gripper['max_opening'] - open_tolerance
        self.state = state
        self.target = self.position = float(spec.gpo_open) if wide else self.scale.position(state['opening'])
        self.motion = AT_TARGET if wide else state['motion']

    def _show(self, state):
        self.state = state
        self.motion = state['motion']
        self.position = self.target if self.motion == AT_TARGET else self.scale.position(state['opening'])
        return self.motion

    def go(self, target, speed, force):
        low, high = self.force_range
        self.target, self.speed = float(target), float(speed) / self.scale.counts_per_metre
        self.force = low + (high - low) * min(max(float(force), 0.0), 1.0)
        self._commanded_at, self.state = self.client.finger(self.scale.opening(self.target), self.speed,
                                                            self.force)
        # Moving until the cell has stepped and advance() says otherwise.
        self.position, self.motion = self.scale.position(self.state['opening']), MOVING

    def stop(self):
        if self.motion == MOVING:
            opening = self.client.finger()[1]['opening']
            self.target = self.scale.position(opening)
            self._commanded_at, state = self.client.finger(opening, self.speed, self.force)
            self._show(state)

    def advance(self, dt, at=None):
        if at is None or self.sample_period is None:
            return self._show(self.client.finger()[1])
        if at <= self._commanded_at + SAME_TIME:
            return self.motion  # a status due before the last command, served late: the command's own
        return self._show(self._kept_at(at))

    def _kept_at(self, at, tolerance=SAME_TIME):
        """The state the cell kept for time `at` (none from before the last command); the state now if the cell
        has not reached `at` yet (it is at most a control cycle behind this node's clock).

        A sample stamped with the command's own time was taken before it, at the end of the cycle that the
        command followed: it shows the fingers at the last target, and would read as having arrived."""
        waiting, now = self._waiting, None
        if not waiting or waiting[-1][0] < at - tolerance:
            _, samples, _, now = self.client.finger_samples(self.sample_period)
            waiting.extend(samples)
        while waiting and (waiting[0][0] < at - tolerance or waiting[0][0] <= self._commanded_at + tolerance):
            waiting.popleft()
        if waiting:
            return waiting.popleft()[1] if waiting[0][0] <= at + tolerance else waiting[0][1]
        return now if now is not None else self.client.finger()[1]

    def squeeze(self):
        # Asked while the register machine holds an object: the drive's force, also while a held part
        # rocks the fingers (the cell then says MOVING).
        return min(self.state['grip_force'] / self.force_range[1], 1.0)


class RegisterGripper(object):
    """The 2F-140's registers (no ROS) over `fingers` (default: KinematicFingers). Time in seconds, from `advance`."""

    def __init__(self, spec, log_warn, object_width=None, initial_position=None,
                 clock=time.monotonic, fingers=None):
        self.spec = spec
        self._warn = log_warn
        self._clock = clock
        self._last_warning = {}
        self.fingers = fingers or KinematicFingers(spec, object_width, initial_position)
        self.command = dict.fromkeys(COMMAND_FIELDS, 0)
        self.state = 'reset'  # reset, activating, active, releasing, released
        self.activation_left = 0.0
        self.fault = FAULT_NONE
        self.object_status = 0
        self.moving = False
        self.holding = False
        self.held_at = None  # gPO (counts) where the fingers stopped on the object they hold
        self.closing = False

    @property
    def position(self):
        """gPO before rounding: where the fingers are, in register counts."""
        return self.fingers.position

    # -- commands ------------------------------------------------------------

    def _bit(self, name, value):
        if value in (0, 1):
            return value
        now = self._clock()
        if now - self._last_warning.get(name, -math.inf) >= RATE_LIMIT:
            self._last_warning[name] = now
            self._warn('gripper_sim: %s=%d is not a bit; taken as 1, as Robotiq\'s driver sends it '
                       '(send 0 or 1)' % (name, value))
        return 1

    def set_command(self, registers):
        """Take a Robotiq2FGripper_robot_output as a dict of its six fields."""
        values = {name: int(registers[name]) for name in COMMAND_FIELDS}
        for name in BITS:
            values[name] = self._bit(name, values[name])
        for name in ('rPR', 'rSP', 'rFR'):
            values[name] = min(max(values[name], 0), 255)
        previous, self.command = self.command, values
        if values['rACT'] == 0:
            self._reset()
            return
        if previous['rACT'] == 0 and self.state == 'reset':
            self.state = 'activating'
            self.activation_left = self.spec.activation_time
            self.moving = False
        if self.state in ('releasing', 'released'):
            return  # the automatic release overrides everything but rACT
        if values['rATR']:
            self.state = 'releasing'
            self.fault = FAULT_AUTO_RELEASE_ACTIVE
            # To the mechanical end beyond the software limit, slowly.
            self.fingers.go(0.0, self.spec.speed_counts(0), values['rFR'] / 255.0)
            self.moving, self.holding = True, False
            return
        if self.state == 'active':
            self._request(previous)

    def _reset(self):
        self.state = 'reset'
        self.fault = FAULT_NONE
        self.object_status = 0
        self.moving = self.holding = False
        self.fingers.stop()

    def _request(self, previous):
        """A command while active: start, change or stop a motion."""
        c = self.command
        if not c['rGTO']:
            self.moving = False
            self.fingers.stop()
            self.object_status = 3 if not self.holding else self.object_status
            return
        if previous['rGTO'] and all(c[k] == previous[k] for k in ('rPR', 'rSP', 'rFR')):
            return
        target = float(min(max(c['rPR'], self.spec.gpo_open), self.spec.gpo_closed))
        closing = target > self.position
        if self.holding and closing:
            return  # still squeezing the object: nothing changes
        self.fingers.go(target, self.spec.speed_counts(c['rSP']), c['rFR'] / 255.0)
        self.closing = closing
        self.holding = False
        self.moving = True
        self.object_status = 0

    # -- time ----------------------------------------------------------------

    def advance(self, dt, at=None):
        """Let `dt` seconds pass; `at`: the simulated time they end at, on a simulated clock."""
        dt = max(float(dt), 0.0)
        c = self.command
        if self.state == 'activating':
            self.activation_left -= dt
            if c['rGTO']:
                self.fault = FAULT_ACTION_DELAYED
            if self.activation_left <= 0.0:
                self.state = 'active'
                self.fault = FAULT_NONE
                self._request(dict(c, rGTO=0))  # a request made while activating runs now
            return
        if self.state == 'reset':
            self.fault = FAULT_ACTIVATION_BIT if c['rGTO'] else FAULT_NONE
            return
        if self.state == 'released' or not (self.moving or self.holding):
            return
        motion = self.fingers.advance(dt, at)
        if self.state == 'releasing':
            if motion != MOVING:
                self.state, self.fault, self.moving = 'released', FAULT_AUTO_RELEASE_DONE, False
            return
        if motion == ON_OBJECT and self.moving:
            self.moving, self.holding, self.object_status = False, True, 2 if self.closing else 1
            self.held_at = self.position
        elif motion == AT_TARGET:
            # Arrived, or a held object was lost and the fingers went on to the request.
            self.moving, self.holding, self.object_status = False, False, 3
        elif motion == MOVING and self.holding and self._lost_hold():
            self.moving, self.holding, self.object_status = True, False, 0

    def _lost_hold(self):
        """Whether the holding fingers have travelled OBJECT_LOST_TRAVEL on towards the request."""
        on = self.position - self.held_at if self.closing else self.held_at - self.position
        return on > OBJECT_LOST_TRAVEL * self.spec.scale.counts_per_metre

    # -- status --------------------------------------------------------------

    def status(self):
        """Robotiq2FGripper_robot_input fields as a dict."""
        c = self.command
        active = self.state == 'active'
        if self.moving and self.state in ('active', 'releasing'):
            current = self.spec.moving_current
        elif self.holding and active:
            current = self.spec.max_grip_current * self.fingers.squeeze()
        else:
            current = 0
        return dict(
            gACT=c['rACT'],
            gGTO=c['rGTO'] if active else 0,
            gSTA={'reset': 0, 'activating': 1, 'active': 3}.get(self.state, 0),
            gOBJ=self.object_status if active else 0,
            gFLT=self.fault,
            gPR=c['rPR'] if c['rACT'] else 0,
            gPO=int(round(min(max(self.position, 0.0), 255.0))),
            gCU=int(round(current)))


PARAMETERS = (
    sim_params.Param('~rate', 50.0, 'Status publishing rate (Hz) on Robotiq2FGripperRobotInput',
                     sim_params.number(strictly_above=0.0)),
    sim_params.Param('~object_width', None, 'Width (m) of a part between the pads: closing stops on it (gOBJ 2); '
                     'unset: none; not with ~physics, where the fingers stop on the world\'s objects',
                     sim_params.unset_or(sim_params.number(minimum=0.0))),
    sim_params.Param('~initial_position', sim_params.StartupDefault('the gripper\'s `gpo_open` in ~devices_file'),
                     'gPO at start-up, in reset as after a power-up; not with ~physics',
                     sim_params.number(minimum=0.0)),
    sim_params.Param('~urcap_address', '', 'IPv4 address of the simulated robot, where the gripper URCap\'s socket '
                     'listens (config/robotiq_2f_urcap.yaml\'s port, 63352): SET and GET on the same registers as '
                     'this node\'s topics; empty: none'),
    sim_params.Param('~modbus_rtu_port', '', 'Path of a serial port where the gripper answers Modbus RTU as on its '
                     'RS-485 line (slave 9, config/robotiq_2f_modbus.yaml): a symbolic link made there to a '
                     'pseudo-terminal, for Robotiq\'s Modbus RTU node or any client; empty: none'),
    sim_params.Param('~modbus_tcp_address', '', 'IPv4 address where the gripper answers Modbus TCP as Robotiq\'s '
                     'gateway serves it (registers from 0); empty: none'),
    sim_params.Param('~modbus_tcp_port', 502, 'TCP port of ~modbus_tcp_address: the gateway\'s 502, which needs '
                     'privileges; e.g. 5020 for a client that takes a port', sim_params.number(minimum=0)),
    sim_params.PHYSICS,
    sim_params.DEVICES_FILE,
)


def spec_from_params(get_param):
    return sim_params.from_devices_file(get_param, PARAMETERS, lambda path: GripperSpec(
        gripper_model.load_gripper_spec(path, GripperSpec.KEYS)))


def settings_from_params(get_param):
    """(spec, rate, object_width, initial_position) from private parameters; ParamError if bad."""
    spec = spec_from_params(get_param)
    rate = sim_params.read(get_param, PARAMETERS, '~rate')
    width = sim_params.read(get_param, PARAMETERS, '~object_width')
    if width is not None and width > spec.stroke:
        raise sim_params.ParamError('~object_width=%r m is wider than the %g m stroke: the '
                                    'gripper could not hold it' % (width, spec.stroke))
    initial = sim_params.read(get_param, PARAMETERS, '~initial_position', default=spec.gpo_open)
    if initial > 255:
        raise sim_params.ParamError('~initial_position=%r must be a position register value '
                                    '0..255' % (initial,))
    return spec, rate, width, initial


def start_urcap_socket(address, gripper, lock, log, port=None):
    """The gripper URCap's socket over `gripper` (a RegisterGripper) at `address`, serving in a thread of its own;
    listen.ListenError (one line) when it cannot listen."""
    table = robotiq_urcap.read_table()
    server = robotiq_urcap.serve(listen.checked_address(address), robotiq_urcap.UrcapGripper(table, gripper, lock),
                                 log, table['port'] if port is None else port)
    threading.Thread(target=server.serve_forever, name='urcap socket', daemon=True).start()
    return server


def start_modbus_faces(get_param, gripper, lock, log):
    """The Modbus faces the parameters ask for, serving in threads of their own: [(what, where, server)];
    listen.ListenError or modbus_line.ModbusUnavailable (one line) when one cannot start."""
    port = sim_params.read(get_param, PARAMETERS, '~modbus_rtu_port')
    address = sim_params.read(get_param, PARAMETERS, '~modbus_tcp_address')
    if not (port or address):
        return []
    table = robotiq_modbus.read_table()
    faces = []
    try:
        if port:
            line = robotiq_modbus.serve_rtu(table, gripper, lock, log, link=port)
            faces.append(('Modbus RTU (slave %d, %d 8N1)' % (table['rtu']['slave_id'],
                                                            table['rtu']['serial']['baudrate']),
                          "%s (%s): for Robotiq's Modbus RTU node, the real bring-up's gripper_device:=%s"
                          % (port, line.path, port), line))
        if address:
            server = robotiq_modbus.serve_tcp(table, gripper, lock, log, listen.checked_address(address),
                                              int(sim_params.read(get_param, PARAMETERS, '~modbus_tcp_port')))
            host, tcp_port = server.server_address[:2]
            faces.append(('Modbus TCP', "%s:%d: for Robotiq's Modbus TCP node (port 502 only), the real bring-up's "
                          'gripper_ip:=%s' % (host, tcp_port, host), server))
    except Exception:
        for _, _, face in faces:
            face.shutdown()
        raise
    return faces


def run(rospy):
    """The node: parameters, subscriber, status loop. Returns the exit status."""
    from robotiq_2f_gripper_control.msg import (Robotiq2FGripper_robot_input,
                                                Robotiq2FGripper_robot_output)

    try:
        spec, rate, width, initial = settings_from_params(rospy.get_param)
    except sim_params.ParamError as exc:
        rospy.logfatal('gripper_sim: bad parameter %s', exc)
        return 1
    fingers, lost = None, []
    if sim_params.read(rospy.get_param, PARAMETERS, '~physics'):
        if width is not None:
            rospy.logwarn('gripper_sim: ~object_width is not used with ~physics: the fingers stop on the '
                          "world's objects")
            width = None
        client = link.wait_for_cell(rospy, 'gripper_sim')
        if client is None:
            return 0
        if client.info['gripper'] is None:
            rospy.logfatal("gripper_sim: the physics cell's model has no 2F-140: start the arm with the "
                           'model that has it (gripper:=true)')
            return 1
        # On the simulated clock each status shows the fingers at its own time (run_on_every_tick below).
        fingers = PhysicsFingers(client, spec, sample_period=1.0 / rate if rospy.get_param('/use_sim_time', False)
                                 else None)
    gripper = RegisterGripper(spec, rospy.logwarn, object_width=width, initial_position=initial, fingers=fingers)
    # Five seconds of statuses at 50 Hz, as the FT 300 keeps five of its 100 Hz: on a simulated clock
    # faster than real time a subscriber starved for a moment gets every tick late, not a gap.
    publisher = rospy.Publisher('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input,
                                queue_size=256)

    lock = threading.Lock()  # callbacks and the URCap socket's sessions run in threads of their own, the loop in this one
    address = sim_params.read(rospy.get_param, PARAMETERS, '~urcap_address')
    if address:
        try:
            server = start_urcap_socket(address, gripper, lock, rospy.logwarn)
        except listen.ListenError as exc:
            rospy.logfatal('gripper_sim: %s', exc)
            return 1
        rospy.on_shutdown(server.shutdown)
        rospy.loginfo("gripper_sim: the gripper URCap's socket listens on %s:%d", *server.server_address[:2])
    try:
        faces = start_modbus_faces(rospy.get_param, gripper, lock, rospy.logwarn)
    except (listen.ListenError, modbus_line.ModbusUnavailable, sim_params.ParamError) as exc:
        rospy.logfatal('gripper_sim: %s', exc)
        return 1
    for what, where, face in faces:
        rospy.on_shutdown(face.shutdown)
        rospy.loginfo('gripper_sim: the 2F-140 answers %s on %s', what, where)

    def on_command(msg):
        with lock:
            if lost:
                return
            try:
                gripper.set_command({name: getattr(msg, name) for name in COMMAND_FIELDS})
            except link.LinkError as exc:
                lost.append(link.lost_cell(rospy, 'gripper_sim', exc))

    rospy.Subscriber('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output, on_command,
                     queue_size=100)
    rospy.loginfo('gripper_sim: 2F-140 in reset at gPO %d%s; activate with rACT 1 on '
                  'Robotiq2FGripperRobotOutput', int(round(gripper.position)),
                  ', on the physics cell' if fingers else
                  '' if width is None else ', object of %g m between the pads' % width)
    message = Robotiq2FGripper_robot_input()

    def publish_after(dt, at=None):
        """Let `dt` s pass in the register machine (to simulated time `at`), then publish its status."""
        with lock:
            if lost:
                return
            try:
                gripper.advance(dt, at)
            except link.LinkError as exc:
                lost.append(link.lost_cell(rospy, 'gripper_sim', exc))
                return
            status = gripper.status()
        for name, value in status.items():
            setattr(message, name, value)
        publisher.publish(message)

    if rospy.get_param('/use_sim_time', False):
        # One status per period of simulated time, each a period later than the last, however late
        # this node runs; a command takes effect at the cell's next control cycle (physics) or this
        # node's next tick.
        period = 1.0 / rate
        status = node_loop.run_on_every_tick(rospy, rate, lambda stamp: publish_after(period, stamp.to_sec()))
    else:
        # On the wall clock too a status per period, those of a stretch the node ran late served late: the
        # register machine moves on by the time between two ticks (a second at most: a machine that slept).
        clock = {'time': None}

        def step(stamp):
            last, clock['time'] = clock['time'], stamp
            publish_after(0.0 if last is None else (stamp - last).to_sec())

        def restart_clock():
            clock['time'] = None

        status = node_loop.run_on_every_tick(rospy, rate, step, on_time_jump=restart_clock,
                                             max_backlog=int(rate))
    return 1 if lost else status


def main():
    return node_loop.main('robotiq2FGripper', run)
