"""The simulated cell on MuJoCo: export_mjcf's robot and a world in one model, without ROS.

``Cell`` steps the model in whole timesteps (``config/physics.yaml``'s
``solver.timestep``) and offers what the three simulated devices need:

* the arm: a servo reference (position and velocity of every arm joint),
  which the model's servos follow; the joints' positions, velocities and
  efforts (N m, the actuators' torques, gravity compensation included); a
  protective stop when the robot's net contact force with the world exceeds
  ``arm.protective_stop_force``, after which the servos hold the arm where it
  stopped until ``clear_protective_stop``;
* the FT 300: ``wrench()``, MuJoCo's force and torque at the sensor frame in
  the sensor's axes, with the sign of ``devices/wrench_model.py`` (what the
  tool side exerts on the sensor: a hanging mass pulls along +z when the
  sensor's z points down): the tool side's weight and inertia, contacts, and
  whatever the fingers hold; and ``keep_wrench_samples(period)``, after which
  the cell records that reading at every simulated time that is a whole
  multiple of `period`, for ``take_wrench_samples()``: the FT 300's node
  publishes one reading per period of simulated time, stamped with it,
  however late its own process runs;
* the flange: ``flange_wrench()``, the same at ``tool0``: what everything
  mounted on the arm exerts on it, the reading the simulated robot's own
  wrench starts from;
* the 2F-140: ``command_finger(opening, speed, force)`` moves a target along
  the pad gap at `speed`, which finger_joint's servo follows with its torque
  capped at what squeezes with `force` (by virtual work, the torque is the
  force times d(gap)/d(angle), from the model's own GripperKinematics);
  ``finger()`` says where the fingers are and whether they reached the
  target, stopped on an object, or are moving; ``keep_finger_samples(period)``
  and ``take_finger_samples()`` keep it at every multiple of `period`, for the
  2F-140's node as the wrench's samples are for the FT 300's;
* the world: ``object_pose(name)``.

Time is counted in whole timesteps (``time`` is their number times the
timestep, without the drift of a float summed step by step).
"""

import collections
import math
import os
import shutil
import tempfile
import xml.etree.ElementTree as ElementTree

import numpy as np

from ... import kinematics
from ...model import description, mjcf
from ...model.names import FINGER_JOINT, FLANGE
from ..gripper_model import GripperKinematics
from . import require_mujoco
from .world import WorldError, empty_world, overlap_problem

# Contacts at the start up to this deep are contact, not overlap (m): MuJoCo's
# soft contacts let resting bodies sink a fraction of a millimetre.
OVERLAP_TOLERANCE = 0.001
# The fingers count as stopped once finger_joint has stayed within STALL_TRAVEL (rad) of one angle for
# STALL_TIME (s). A travel over a window, not a speed: under MuJoCo 3.2.3 a held can rocks in the pads at
# 30 to 40 Hz (up to 2.5 mrad peak to peak, at up to 0.4 rad/s) and goes nowhere. The slowest close (rSP 0,
# 30 mm/s: about 0.15 rad/s) leaves the band in a third of STALL_TIME.
STALL_TRAVEL = 0.005
STALL_TIME = 0.1

MOVING, AT_TARGET, ON_OBJECT = 'moving', 'at_target', 'on_object'


def _sensor_slice(m, name):
    """The slice of MjData.sensordata that sensor `name` fills."""
    start = m.sensor_adr[m.sensor(name).id]
    return slice(start, start + m.sensor_dim[m.sensor(name).id])


def _index(ids):
    """A slice for ascending consecutive ids (numpy takes it without a copy), else an index array."""
    ids = [int(i) for i in ids]
    if ids and ids == list(range(ids[0], ids[0] + len(ids))):
        return slice(ids[0], ids[0] + len(ids))
    return np.array(ids, dtype=int)


class FingerState(object):
    """Where the 2F-140's fingers are and what they are doing.

    opening (m, the pad gap through GripperKinematics), angle (rad) and
    velocity (rad/s) of finger_joint; torque (N m) of its drive and the
    grip force (N) that torque makes; target (m) and ramp (m, where the
    moving target is now); motion: MOVING, AT_TARGET (stopped within the
    tolerance of the target) or ON_OBJECT (stopped short of it, against
    something, closing or opening: see `closing`).
    """

    def __init__(self, **fields):
        self.__dict__.update(fields)

    def __repr__(self):
        return 'FingerState(%s)' % ', '.join('%s=%r' % item for item in sorted(self.__dict__.items()))


class WaitingSamples(object):
    """Samples kept for a reader that takes them in batches: at most `keep` wait, and beyond that the oldest
    are dropped and counted, so a reader that stalls costs bounded memory and learns what it missed."""

    def __init__(self, keep, what):
        if int(keep) < 1:
            raise ValueError('keep %r %s samples: at least one' % (keep, what))
        self._samples, self._dropped = collections.deque(maxlen=int(keep)), 0

    def append(self, sample):
        if len(self._samples) == self._samples.maxlen:
            self._dropped += 1
        self._samples.append(sample)

    def take(self):
        """(samples, dropped): those kept since the last take, oldest first, and how many the bound dropped."""
        samples, dropped = list(self._samples), self._dropped
        self._samples.clear()
        self._dropped = 0
        return samples, dropped


class Cell(object):
    """The robot of `mjcf_path` (export_mjcf's file of the model `urdf_text`) in `world`."""

    def __init__(self, mjcf_path, urdf_text, world=None, prefix='', initial_arm=None, figures=None):
        self.mujoco = require_mujoco()
        self.figures = figures or mjcf.load_physics_figures()
        self.world = world or empty_world()
        root = ElementTree.parse(mjcf_path).getroot()
        robot_bodies = [body.get('name') for body in root.iter('body')]
        self.world.add_to_mjcf(root)
        try:
            self.model = self.mujoco.MjModel.from_xml_string(ElementTree.tostring(root, encoding='unicode'))
        except ValueError as exc:
            raise WorldError('%s: MuJoCo cannot load the cell: %s' % (
                self.world.path, ' '.join(str(exc).split()))) from None
        self.data = self.mujoco.MjData(self.model)
        # The arrays stepped through at every timestep, taken once: each attribute access makes a new view.
        self._ctrl, self._qpos, self._qvel = self.data.ctrl, self.data.qpos, self.data.qvel
        self._qpos_view, self._qvel_view = memoryview(self._qpos), memoryview(self._qvel)
        self._cfrc_ext, self._sensordata = self.data.cfrc_ext, self.data.sensordata
        self._actfrcrange = self.model.jnt_actfrcrange
        self.timestep = float(self.model.opt.timestep)
        self._steps = 0  # timesteps taken: the time without a float's summed rounding
        self._debt = 0.0
        self._contact_force_sums = (0.0, 0.0, 0.0)  # N, summed over the timesteps: contact_impulse()
        m = self.model
        # MuJoCo computes the bodies' contact forces (cfrc_ext) only for a sensor that needs them: the
        # FT 300's. Without one, the cell has them computed after each timestep, for the protective stop.
        needs = {int(self.mujoco.mjtSensor.mjSENS_FORCE), int(self.mujoco.mjtSensor.mjSENS_TORQUE),
                 int(self.mujoco.mjtSensor.mjSENS_ACCELEROMETER), int(self.mujoco.mjtSensor.mjSENS_FRAMELINACC),
                 int(self.mujoco.mjtSensor.mjSENS_FRAMEANGACC)}
        self._compute_contact_forces = not needs.intersection(int(t) for t in m.sensor_type)

        # -- the arm: every position servo with a velocity gain beside it
        self.finger_joint = prefix + FINGER_JOINT
        names = [m.actuator(i).name for i in range(m.nu)]
        self.arm_joints = [n for n in names if n + mjcf.VELOCITY_SUFFIX in names and n != self.finger_joint]
        self._arm_position_ctrl = _index([m.actuator(n).id for n in self.arm_joints])
        self._arm_velocity_ctrl = _index([m.actuator(n + mjcf.VELOCITY_SUFFIX).id for n in self.arm_joints])
        joint_ids = [m.joint(n).id for n in self.arm_joints]
        self._arm_qpos = _index([m.jnt_qposadr[j] for j in joint_ids])
        self._arm_dofs = _index([m.jnt_dofadr[j] for j in joint_ids])
        self._arm_kp = np.array([m.actuator(n).gainprm[0] for n in self.arm_joints])
        self._arm_kv = np.array([m.actuator(n + mjcf.VELOCITY_SUFFIX).gainprm[0] for n in self.arm_joints])
        # Views of the arm's parts of ctrl and of the dofs' arrays, which MuJoCo's vector functions write
        # into at every timestep: export_mjcf writes the arm's joints and servos in order.
        if not all(isinstance(ids, slice) for ids in (self._arm_position_ctrl, self._arm_velocity_ctrl,
                                                       self._arm_dofs)):
            raise ValueError('the arm\'s joints %s are not consecutive joints with consecutive servos in the '
                             'model: a model that export_mjcf did not write?' % ', '.join(self.arm_joints))
        self._arm_position_servo = self._ctrl[self._arm_position_ctrl]
        self._arm_velocity_servo = self._ctrl[self._arm_velocity_ctrl]
        # The inertia feedforward's change of velocity and torque of every dof, made once, and their arm
        # parts; per number of timesteps a call, the factors 1 / (kp T) that turn the torque into the
        # position servo's offset.
        self._feedforward, self._feedforward_torque = np.zeros(m.nv), np.zeros(m.nv)
        self._arm_feedforward = self._feedforward[self._arm_dofs]
        self._arm_feedforward_torque = self._feedforward_torque[self._arm_dofs]
        self._offsets_per_torque = {}
        # How far the servos' reference goes over a step() call, and where it starts (feedforward included).
        self._reference_change, self._reference_origin = np.zeros(len(self.arm_joints)), np.zeros(len(self.arm_joints))
        # The reference: where the servos' reference is now (the start of the next call), where it goes
        # next and its velocity; made once, set_arm_reference and step() copy into them.
        self._reference, self._next_reference = np.zeros(len(self.arm_joints)), np.zeros(len(self.arm_joints))
        self._reference_velocity = np.zeros(len(self.arm_joints))
        # Memoryviews of the arrays that step() copies, compares, reads or writes a few values of between
        # two MuJoCo steps: a memoryview's copy, comparison or item costs a fraction of a numpy call.
        self._reference_view = memoryview(self._reference)
        self._next_reference_view = memoryview(self._next_reference)
        self._reference_velocity_view = memoryview(self._reference_velocity)
        self._position_servo_view = memoryview(self._arm_position_servo)
        self._velocity_servo_view = memoryview(self._arm_velocity_servo)
        self._arm_feedforward_view = memoryview(self._arm_feedforward)
        self._arm_feedforward_torque_view = memoryview(self._arm_feedforward_torque)
        self._reference_origin_view = memoryview(self._reference_origin)
        self._arm_range = range(len(self.arm_joints))
        self.arm_lower = np.array([m.jnt_range[j][0] for j in joint_ids])
        self.arm_upper = np.array([m.jnt_range[j][1] for j in joint_ids])
        self.urdf_text = urdf_text
        urdf = kinematics.Model(urdf_text)
        self.arm_velocity_limits = np.array([urdf.joints[n].limit.velocity for n in self.arm_joints])
        self.robot_bodies = np.array([m.body(n).id for n in robot_bodies])
        # The robot's net external wrench (cfrc_ext's sum over its bodies) is this row times cfrc_ext.
        self._robot_rows = np.zeros(m.nbody)
        self._robot_rows[self.robot_bodies] = 1.0
        self._net_wrench = np.zeros(6)
        self._net_wrench_view = memoryview(self._net_wrench)
        self.protective_stop_force = float(self.figures['arm']['protective_stop_force'])
        self.protective_stop = None

        # -- the FT 300
        frame = prefix + mjcf.ft_sensor_frame()
        self.ft_frame = frame if frame in robot_bodies else None
        if self.ft_frame:
            self._force = slice(m.sensor_adr[m.sensor(frame + mjcf.FORCE_SUFFIX).id],
                                m.sensor_adr[m.sensor(frame + mjcf.FORCE_SUFFIX).id] + 3)
            self._torque = slice(m.sensor_adr[m.sensor(frame + mjcf.TORQUE_SUFFIX).id],
                                 m.sensor_adr[m.sensor(frame + mjcf.TORQUE_SUFFIX).id] + 3)
            self._accelerometer = _sensor_slice(m, frame + mjcf.ACCELEROMETER_SUFFIX)
        flange = prefix + FLANGE
        self._flange_force = _sensor_slice(m, flange + mjcf.FORCE_SUFFIX)
        self._flange_torque = _sensor_slice(m, flange + mjcf.TORQUE_SUFFIX)
        self.wrench_sample_period = None
        self._wrench_samples = None
        self._sample_every, self._next_sample = None, 0  # 0: none kept (step() compares it with 1 and on)
        self.finger_sample_period, self._finger_samples = None, None
        self._next_finger_sample, self._next_finger_sample_time = 0, math.inf

        # -- the 2F-140
        self.gripper = None
        self._has_gripper = False  # gripper is not None as a bool: step() need not touch the gripper's object
        if self.finger_joint in names:
            self.gripper = GripperKinematics(urdf_text, prefix)
            self._has_gripper = True
            self.gripper_base = self.gripper.model.joints[self.finger_joint].parent
            self._rates = np.abs(np.gradient(self.gripper.openings, self.gripper.angles))
            # The finger drive's tables as Python lists, for a lookup at every timestep without numpy's
            # per-call cost (np.interp's own arithmetic: rate = slope * (angle - angle_j) + rate_j).
            self._rate_angles, self._rate_values = self.gripper.angles.tolist(), self._rates.tolist()
            self._rate_spacing = (len(self._rate_angles) - 1) / (self._rate_angles[-1] - self._rate_angles[0])
            self._rate_slopes = ((self._rates[1:] - self._rates[:-1]) /
                                 (self.gripper.angles[1:] - self.gripper.angles[:-1])).tolist()
            self._finger_segment = (0.0, 0.0, 0.0, 0.0, 0.0)  # none yet: the first timestep finds its own
            self._increasing_openings = -self.gripper.openings  # GripperKinematics.angle's table, made once
            self._finger_still = False  # whether the drive's velocity input is 0 since the ramp's end
            self._finger_ramping = True  # whether the drive's target moves along a ramp (command_finger)
            joint = m.joint(self.finger_joint).id
            self._finger_joint = joint
            self._finger_qpos = int(m.jnt_qposadr[joint])
            self._finger_dof = int(m.jnt_dofadr[joint])
            self._finger_ctrl = m.actuator(self.finger_joint).id
            self._finger_velocity_ctrl = m.actuator(self.finger_joint + mjcf.VELOCITY_SUFFIX).id
            m.jnt_actfrclimited[joint] = 1
            self._finger_torque_range = self._actfrcrange[joint]
            self._finger_torque_range_view = memoryview(self._finger_torque_range)
            gripper = self.figures['gripper']
            self.grip_force_range = (float(gripper['grip_force_min']), float(gripper['grip_force_max']))
            self.finger_tolerance = float(gripper['target_tolerance'])
            self._finger = dict(target=None, ramp=None, angle=None, speed=0.0,
                                force=self.grip_force_range[0], closing=False, stalled=0.0, still_at=0.0)

        # -- the world's objects
        self._objects = {solid.name: m.body(solid.name).id for solid in self.world.objects}

        initial = np.zeros(len(self.arm_joints)) if initial_arm is None else np.asarray(initial_arm, float)
        self._start(initial)

    # -- construction -------------------------------------------------------------

    @classmethod
    def build(cls, mappings=None, world=None, initial_arm=None, figures=None):
        """The cell of the package's model for `mappings` (export_model_mappings' keys) in `world`."""
        from ...model import export
        mappings = export.model_mappings(**(mappings or {}))
        return cls._of_document(description.expand_model(mappings), mappings, world, initial_arm, figures)

    @classmethod
    def from_description(cls, urdf_text, ur_type, prefix='', world=None, initial_arm=None, figures=None):
        """The cell of a model as loaded (robot_description: the user's calibration, ur_type and prefix).

        The MJCF is written from that URDF itself, not from the xacro expanded again; which parts
        are mounted is read from its links, the collision exclusions are ur_type's.
        """
        from xml.dom import minidom
        doc = minidom.parseString(urdf_text)
        links = {link.getAttribute('name') for link in doc.getElementsByTagName('link')}
        joints = {joint.getAttribute('name') for joint in doc.getElementsByTagName('joint')}
        mappings = dict(ur_type=ur_type, prefix=prefix,
                        ft_sensor=str(prefix + mjcf.ft_sensor_frame() in links).lower(),
                        gripper=str(prefix + FINGER_JOINT in joints).lower())
        return cls._of_document(doc, mappings, world, initial_arm, figures)

    @classmethod
    def _of_document(cls, doc, mappings, world, initial_arm, figures):
        folder = tempfile.mkdtemp(prefix='ur3_ft_gripper_cell_')
        try:
            path = os.path.join(folder, 'robot.xml')
            mjcf.write_mjcf(doc, mappings, path, figures=figures)
            return cls(path, description.to_xml(doc), world, mappings.get('prefix', ''), initial_arm, figures)
        finally:
            shutil.rmtree(folder, ignore_errors=True)

    def _start(self, arm):
        m, d = self.model, self.data
        if arm.shape != (len(self.arm_joints),) or np.any(arm < self.arm_lower) or np.any(arm > self.arm_upper):
            raise ValueError('initial arm position %r: need %d positions within the joints\' limits'
                             % (arm.tolist(), len(self.arm_joints)))
        d.qpos[self._arm_qpos] = arm
        self._hold_reference()
        if self.gripper is not None:
            opening = self.gripper.opening(d.qpos[self._finger_qpos])
            self._finger.update(target=opening, ramp=opening)
            self._ramp_finger(0.0)
            self._finger_ramping = False
            self._limit_finger_torque()
        self.mujoco.mj_forward(m, d)
        depths = [self._contact_depth(i) for i in range(d.ncon)]
        problem = overlap_problem(self.world, [p for p in depths if p is not None], OVERLAP_TOLERANCE)
        if problem:
            raise WorldError(problem)

    def _contact_depth(self, i):
        """(name, other, depth) of contact i if it involves the world, else None."""
        contact = self.data.contact[i]
        names = []
        for geom in (contact.geom1, contact.geom2):
            body = self.model.geom_bodyid[geom]
            names.append(self.model.geom(geom).name if body == 0 else self.model.body(body).name)
        world = {solid.name for solid in self.world.solids}
        if not world.intersection(names):
            return None
        return names[0], names[1], -float(contact.dist)

    # -- time ---------------------------------------------------------------------

    @property
    def time(self):
        """Simulated time (s): the timesteps taken times the timestep."""
        return self._steps * self.timestep

    def step(self, dt):
        """Let `dt` seconds pass in whole timesteps (the remainder is carried over); returns how many."""
        # This loop is the cell's whole cost beside MuJoCo's (bench/physics.py measures the two side by
        # side): at every timestep only what changes from one to the next, in as little code as may be.
        # Between two MuJoCo steps, which leave little of Python's code and data in the processor's
        # caches, each piece of code run costs more than in a tight loop: a call through MuJoCo's
        # bindings (mju_*) ~1 us, a numpy call 1-1.5 us; a memoryview's copy, comparison or item and
        # Python's float arithmetic much less. Built-in calls (float, max, int, range, abs) cost too:
        # the usual call (a float dt, one timestep) makes none.
        timestep = self.timestep
        if type(dt) is not float:
            dt = float(dt)
        if dt < 0.0:  # max(dt, 0.0), NaN kept
            dt = 0.0
        debt = self._debt + dt
        timesteps = debt / timestep + 1e-9
        steps = 1 if 1.0 <= timesteps < 2.0 else int(timesteps)
        if not steps:
            self._debt = debt
            return 0
        self._debt = debt - steps * timestep
        mujoco, model, data = self.mujoco, self.model, self.data
        # A protective stop already holding the arm keeps its hold reference for the whole call; one
        # tripped in a substep holds the arm from the next substep on.
        following = self.protective_stop is None
        change = None  # how far the reference goes over the call, when it moves
        if following:
            start, start_view = self._reference, self._reference_view
            origin = start  # the position servos' reference at the call's first substep
            # The reference goes linearly from start to its next position over the call's substeps
            # (the first substep has start itself: one substep needs no interpolation).
            if steps > 1 and self._next_reference_view != start_view:
                change = self._reference_change
                mujoco.mju_sub(change, self._next_reference, start)
            # The velocity servos' input is the reference's velocity of the call before.
            if self._reference_velocity_view != self._velocity_servo_view:
                # The servo's inertia feedforward: the torque that accelerating the arm along the reference
                # takes (mass matrix, armature included, times the reference's acceleration), given as an
                # offset of the position servo's reference. Once a call, at the state it starts from: a
                # robot's controller computes it once a control cycle.
                # start + M (v - v_previous) / (kp T): MuJoCo's product, the rest in Python floats through
                # memoryviews (the same arithmetic as MuJoCo's vector functions, in fewer calls).
                velocity, previous = self._reference_velocity_view.tolist(), self._velocity_servo_view.tolist()
                feedforward = self._arm_feedforward_view
                for i in self._arm_range:
                    feedforward[i] = velocity[i] - previous[i]
                mujoco.mj_mulM(model, data, self._feedforward_torque, self._feedforward)
                factors = self._offsets_per_torque.get(steps) or self._offset_per_torque(steps)
                torque, start_values = self._arm_feedforward_torque_view.tolist(), start_view.tolist()
                if change is None:  # held for the whole call: straight into the servos' ctrl
                    origin_view = self._position_servo_view
                else:
                    origin, origin_view = self._reference_origin, self._reference_origin_view
                for i in self._arm_range:
                    origin_view[i] = start_values[i] + torque[i] * factors[i]
                self._velocity_servo_view[:] = self._reference_velocity_view
            elif change is None and self._position_servo_view != start_view:
                self._position_servo_view[:] = start_view
        limit = self.protective_stop_force
        net, robot_rows, cfrc_ext = self._net_wrench, self._robot_rows, self._cfrc_ext
        net_view, servo = self._net_wrench_view, self._arm_position_servo
        sum_x, sum_y, sum_z = self._contact_force_sums
        gripper = self._has_gripper
        if gripper:
            finger, ramping = self._finger, self._finger_ramping
            still, force = self._finger_still, finger['force']
            stalled, still_at = finger['stalled'], finger['still_at']
            qpos, finger_qpos = self._qpos_view, self._finger_qpos
            cap = self._finger_torque_range_view
            # The rates' table segment the fingers are in: gripping, they stay in it for many timesteps.
            segment = self._finger_segment
            low, high, base, slope, rate = segment
        compute_contact_forces = self._compute_contact_forces
        count, next_sample = self._steps, self._next_sample
        k = 0
        while k < steps:  # not a for loop over range(steps): a call
            if change is not None and following:
                mujoco.mju_addScl(servo, origin, change, float(k) / steps)
            if gripper:
                if ramping:
                    ramping, still = self._ramp_finger(timestep), False
                elif not still:
                    self._ctrl[self._finger_velocity_ctrl] = 0.0
                    still = True
                # The drive's torque cap: what squeezes with the commanded force at this angle.
                angle = qpos[finger_qpos]
                if not low <= angle < high:
                    segment = self._rate_segment(angle)
                    low, high, base, slope, rate = segment
                finger_torque = force * (slope * (angle - base) + rate)
                cap[0] = -finger_torque  # two memoryview items: no call
                cap[1] = finger_torque
            mujoco.mj_step(model, data)
            count += 1
            if compute_contact_forces:
                mujoco.mj_rnePostConstraint(model, data)
            mujoco.mju_mulMatTVec(net, cfrc_ext, robot_rows)
            _, _, _, fx, fy, fz = net_view.tolist()
            sum_x += fx
            sum_y += fy
            sum_z += fz
            if following and fx * fx + fy * fy + fz * fz > limit * limit:
                self._stop(math.sqrt(fx * fx + fy * fy + fz * fz))
                following = False
            if gripper:
                angle = qpos[finger_qpos]
                if -STALL_TRAVEL < angle - still_at < STALL_TRAVEL:  # abs(): a call
                    stalled += timestep
                else:
                    still_at, stalled = angle, 0.0
            if count == next_sample:
                self._keep_wrench_sample(count)
                next_sample += self._sample_every
            k += 1
        self._steps, self._next_sample = count, next_sample
        self._contact_force_sums = (sum_x, sum_y, sum_z)
        if gripper:
            finger['stalled'], finger['still_at'], self._finger_still = stalled, still_at, still
            self._finger_segment, self._finger_ramping = segment, ramping
        if following:
            self._reference_view[:] = self._next_reference_view
        if self._finger_samples is not None and count * timestep >= self._next_finger_sample_time:
            self._keep_finger_samples()
        return steps

    def _offset_per_torque(self, steps):
        """[1 / (kp T)], T the duration of `steps` timesteps: M (v - v_previous) times it is the offset."""
        factors = self._offsets_per_torque.get(steps)
        if factors is None:
            factors = self._offsets_per_torque[steps] = (1.0 / (self._arm_kp * (steps * self.timestep))).tolist()
        return factors

    # -- the arm ------------------------------------------------------------------

    @property
    def arm_stiffness(self):
        """The arm's position servos' gains (N m/rad, in arm_joints' order), as a copy."""
        return self._arm_kp.copy()

    @property
    def arm_servo_damping(self):
        """The arm's velocity servos' gains (N m s/rad, in arm_joints' order), as a copy."""
        return self._arm_kv.copy()

    @property
    def arm_position(self):
        return self.data.qpos[self._arm_qpos].copy()

    @property
    def arm_velocity(self):
        return self.data.qvel[self._arm_dofs].copy()

    @property
    def arm_effort(self):
        """Joint torques of the drives (N m), gravity compensation included."""
        return self.data.qfrc_actuator[self._arm_dofs].copy()

    def set_arm_reference(self, position, velocity):
        """Where the servos' reference is at the end of the next step() (linear in between), and its velocity.

        While a protective stop holds the arm, the reference stays where the arm stopped.
        """
        if self.protective_stop is not None:
            return
        try:
            # Copied through memoryviews: the arm's node calls this every cycle, and a memoryview copies
            # an array of as many floats for a fraction of a numpy call.
            self._next_reference_view[:] = position
            self._reference_velocity_view[:] = velocity
        except (TypeError, ValueError):  # anything else (a list, ints): numpy converts it
            self._next_reference[:] = self._arm_values(position, 'position')
            self._reference_velocity[:] = self._arm_values(velocity, 'velocity')

    def _arm_values(self, values, what):
        """`values` as floats, one per arm joint."""
        array = np.asarray(values, dtype=float)
        if array.shape != self._reference.shape:
            raise ValueError('arm reference %s of shape %s: need %d values'
                             % (what, array.shape, len(self._reference)))
        return array

    def _hold_reference(self):
        """Hold the arm where it is now."""
        self._reference[:] = self.arm_position
        self._next_reference[:] = self._reference
        self._reference_velocity[:] = 0.0
        # The servos hold it; the velocity servos' input is also the velocity of the reference before.
        self._arm_position_servo[:] = self._reference
        self._arm_velocity_servo[:] = 0.0

    def contact_force(self):
        """Net force (N, world frame) that the world's contacts put on the robot."""
        net = np.zeros(6)
        self.mujoco.mju_mulMatTVec(net, self._cfrc_ext, self._robot_rows)
        return net[3:]

    def contact_impulse(self):
        """Impulse (N s, world frame) that the world's contacts have put on the robot since the cell began.

        contact_force() summed over every timestep taken, times the timestep: the difference of two
        readings over their time apart is the exact mean force between them, which no sampling of
        contact_force() gives (a contact's force changes from one timestep to the next).
        """
        return np.array(self._contact_force_sums) * self.timestep

    def _stop(self, force):
        self.protective_stop = ('the contact force on the robot, %.0f N, exceeded the %.0f N limit'
                                % (force, self.protective_stop_force))
        self._hold_reference()

    def clear_protective_stop(self):
        """Release the protective stop (the servos then follow the reference again, from where the arm is)."""
        self.protective_stop = None
        self._hold_reference()

    # -- the FT 300 ---------------------------------------------------------------

    def wrench(self):
        """(fx, fy, fz, tx, ty, tz) that the tool side exerts on the FT 300, in its sensor frame."""
        if self.ft_frame is None:
            raise ValueError('the model has no FT 300')
        sensordata = self.data.sensordata
        return -np.concatenate((sensordata[self._force], sensordata[self._torque]))

    def accelerometer(self):
        """(ax, ay, az) m/s^2 that the FT 300's accelerometer reads, in its sensor frame: the specific force,
        its acceleration less gravity's (at rest, gravity's reaction, 9.81 m/s^2 up)."""
        if self.ft_frame is None:
            raise ValueError('the model has no FT 300')
        return self.data.sensordata[self._accelerometer].copy()

    def flange_wrench(self):
        """(fx, fy, fz, tx, ty, tz) that the tool side exerts on the flange (tool0), in tool0's axes."""
        sensordata = self.data.sensordata
        return -np.concatenate((sensordata[self._flange_force], sensordata[self._flange_torque]))

    def keep_wrench_samples(self, period, keep=2000):
        """From now on, record wrench() at every simulated time that is a whole multiple of `period` (s).

        take_wrench_samples() hands them over; at most `keep` wait there, beyond which the oldest are
        dropped and counted. `period` must be a whole number of timesteps. Calling again restarts:
        the samples waiting are discarded.
        """
        if self.ft_frame is None:
            raise ValueError('the model has no FT 300')
        period = float(period)
        every = int(round(period / self.timestep)) if period > 0 and math.isfinite(period) else 0
        if every < 1 or abs(every * self.timestep - period) > 1e-9 * period:
            raise ValueError('wrench sample period %r s: not a whole number of timesteps of %r s'
                             % (period, self.timestep))
        samples = WaitingSamples(keep, 'wrench')
        self.wrench_sample_period, self._sample_every = period, every
        self._next_sample = (self._steps // every + 1) * every
        self._wrench_samples = samples

    def take_wrench_samples(self):
        """(samples, dropped): the samples recorded since the last call and how many of them the bound dropped.

        samples: [(time, (fx, fy, fz, tx, ty, tz), (ax, ay, az)), ...], oldest first, time the timesteps taken
        times the timestep: wrench() and accelerometer() at that time.
        """
        if self._wrench_samples is None:
            raise ValueError('the cell keeps no wrench samples: call keep_wrench_samples first')
        return self._wrench_samples.take()

    def _keep_wrench_sample(self, count):
        sensordata = self._sensordata
        fx, fy, fz = sensordata[self._force].tolist()
        tx, ty, tz = sensordata[self._torque].tolist()
        self._wrench_samples.append((count * self.timestep, (-fx, -fy, -fz, -tx, -ty, -tz),
                                     tuple(sensordata[self._accelerometer].tolist())))

    # -- the 2F-140 ---------------------------------------------------------------

    def keep_finger_samples(self, period, keep=2000):
        """From now on, record finger() for every simulated time that is a whole multiple of `period` (s).

        The 2F-140's node publishes its status once per period of simulated time, each the fingers as
        they were then, however late its own process runs. A sample is taken after the step() that
        reaches its time: the fingers at the end of that control cycle (2 or 8 ms), stamped with the
        multiple. take_finger_samples() hands them over, as take_wrench_samples() does.
        """
        if self.gripper is None:
            raise ValueError('the model has no 2F-140')
        period = float(period)
        if not (period > 0 and math.isfinite(period)):
            raise ValueError('finger sample period %r s: a positive number of seconds' % (period,))
        samples = WaitingSamples(keep, 'finger')
        self.finger_sample_period = period
        self._next_finger_sample = int(math.floor(self.time / period + 1e-9)) + 1
        self._next_finger_sample_time = self._next_finger_sample * period - 1e-9
        self._finger_samples = samples

    def take_finger_samples(self):
        """(samples, dropped): [(time, FingerState), ...] recorded since the last call, oldest first, and how
        many of them the bound dropped."""
        if self._finger_samples is None:
            raise ValueError('the cell keeps no finger samples: call keep_finger_samples first')
        return self._finger_samples.take()

    def _keep_finger_samples(self):
        state, samples, period = self.finger(), self._finger_samples, self.finger_sample_period
        while self._next_finger_sample_time <= self.time:
            samples.append((self._next_finger_sample * period, state))
            self._next_finger_sample += 1
            self._next_finger_sample_time = self._next_finger_sample * period - 1e-9

    def command_finger(self, opening, speed, force):
        """Move the pad gap to `opening` (m) at `speed` (m/s), squeezing with at most `force` (N)."""
        if self.gripper is None:
            raise ValueError('the model has no 2F-140')
        low, high = self.gripper.min_opening, self.gripper.max_opening
        state = self._finger
        current = self.gripper.opening(self.data.qpos[self._finger_qpos])
        state['target'] = min(max(float(opening), low), high)
        state['ramp'], state['angle'] = current, None
        state['speed'] = max(float(speed), 0.0)
        state['force'] = min(max(float(force), self.grip_force_range[0]), self.grip_force_range[1])
        state['closing'] = state['target'] < current
        state['stalled'], state['still_at'] = 0.0, float(self.data.qpos[self._finger_qpos])
        self._finger_ramping = True

    def _rate(self, angle):
        """d(gap)/d(angle) at `angle`: np.interp in the rates' table, its arithmetic in Python floats."""
        _, _, base, slope, rate = self._rate_segment(angle)
        return slope * (angle - base) + rate

    def _rate_segment(self, angle):
        """(low, high, base, slope, rate): the rate is slope * (angle - base) + rate for low <= angle < high.

        The table's segment that np.interp takes for `angle` (constant beyond the table's ends). Its angles
        are evenly spaced: the segment is found from the spacing, then checked against the table.
        """
        angles, rates = self._rate_angles, self._rate_values
        if not angle < angles[-1]:  # at or past the end (or NaN)
            return angles[-1], math.inf, angles[-1], 0.0, rates[-1]
        if angle < angles[0]:
            return -math.inf, angles[0], angles[0], 0.0, rates[0]
        j = min(int((angle - angles[0]) * self._rate_spacing), len(angles) - 2)
        while angles[j] > angle:
            j -= 1
        while angles[j + 1] <= angle:
            j += 1
        return angles[j], angles[j + 1], angles[j], self._rate_slopes[j], rates[j]

    def _ramp_finger(self, dt):
        """Move the drive's target one timestep along the ramp to the commanded opening; True while short of it."""
        ctrl, state = self._ctrl, self._finger
        ramp, target = state['ramp'], state['target']
        step = state['speed'] * dt
        delta = target - ramp
        ramp = target if abs(delta) <= step else ramp + math.copysign(step, delta)
        # GripperKinematics.angle(ramp), its table made once.
        angle = float(np.interp(-float(ramp), self._increasing_openings, self.gripper.angles))
        ctrl[self._finger_velocity_ctrl] = (angle - ctrl[self._finger_ctrl]) / dt if dt > 0 else 0.0
        ctrl[self._finger_ctrl] = angle
        state.update(ramp=ramp, angle=angle)
        return ramp != target

    def _limit_finger_torque(self):
        """Cap the drive's torque at what squeezes with the commanded force at the fingers' angle now."""
        limit = self._finger['force'] * self._rate(self._qpos.item(self._finger_qpos))
        self._finger_torque_range[0] = -limit
        self._finger_torque_range[1] = limit

    def finger(self):
        """The FingerState now."""
        d, state = self.data, self._finger
        angle = float(d.qpos[self._finger_qpos])
        opening = self.gripper.opening(angle)
        torque = float(d.qfrc_actuator[self._finger_dof])
        motion = MOVING
        if state['stalled'] >= STALL_TIME:
            short = (opening - state['target']) if state['closing'] else (state['target'] - opening)
            if abs(opening - state['target']) <= self.finger_tolerance:
                motion = AT_TARGET
            elif short > self.finger_tolerance:
                motion = ON_OBJECT
        return FingerState(opening=opening, angle=angle, velocity=float(d.qvel[self._finger_dof]),
                           torque=torque, grip_force=abs(torque) / self._rate(angle),
                           target=state['target'], ramp=state['ramp'], closing=state['closing'],
                           motion=motion)

    # -- the world ----------------------------------------------------------------

    @property
    def objects(self):
        return sorted(self._objects)

    def object_pose(self, name):
        """(position (m), quaternion w x y z) of object `name` in the world frame."""
        body = self._objects[name]
        return self.data.xpos[body].copy(), self.data.xquat[body].copy()

    def body_pose(self, name):
        """(position, 3x3 rotation) of a body of the model (a link of the robot, an object)."""
        body = self.model.body(name).id
        return self.data.xpos[body].copy(), self.data.xmat[body].reshape(3, 3).copy()
