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
  whatever the fingers hold;
* the 2F-140: ``command_finger(opening, speed, force)`` moves a target along
  the pad gap at `speed`, which finger_joint's servo follows with its torque
  capped at what squeezes with `force` (by virtual work, the torque is the
  force times d(gap)/d(angle), from the model's own GripperKinematics);
  ``finger()`` says where the fingers are and whether they reached the
  target, stopped on an object, or are moving;
* the world: ``object_pose(name)``.
"""

import math
import os
import shutil
import tempfile
import xml.etree.ElementTree as ElementTree

import numpy as np

from ... import kinematics
from ...model import description, mjcf
from ...model.names import FINGER_JOINT
from ..gripper_model import GripperKinematics
from . import require_mujoco
from .world import WorldError, empty_world, overlap_problem

# Contacts at the start up to this deep are contact, not overlap (m): MuJoCo's
# soft contacts let resting bodies sink a fraction of a millimetre.
OVERLAP_TOLERANCE = 0.001
# The fingers count as stopped when slower than this (rad/s) for STALL_TIME (s).
STALL_SPEED = 0.02
STALL_TIME = 0.02

MOVING, AT_TARGET, ON_OBJECT = 'moving', 'at_target', 'on_object'


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
        self._cfrc_ext = self.data.cfrc_ext
        self._actfrcrange = self.model.jnt_actfrcrange
        self.timestep = float(self.model.opt.timestep)
        self._debt = 0.0
        m = self.model

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
        self.arm_lower = np.array([m.jnt_range[j][0] for j in joint_ids])
        self.arm_upper = np.array([m.jnt_range[j][1] for j in joint_ids])
        self.urdf_text = urdf_text
        urdf = kinematics.Model(urdf_text)
        self.arm_velocity_limits = np.array([urdf.joints[n].limit.velocity for n in self.arm_joints])
        self.robot_bodies = np.array([m.body(n).id for n in robot_bodies])
        self._robot_bodies = _index(self.robot_bodies)
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

        # -- the 2F-140
        self.gripper = None
        if self.finger_joint in names:
            self.gripper = GripperKinematics(urdf_text, prefix)
            self.gripper_base = self.gripper.model.joints[self.finger_joint].parent
            self._rates = np.abs(np.gradient(self.gripper.openings, self.gripper.angles))
            joint = m.joint(self.finger_joint).id
            self._finger_joint = joint
            self._finger_qpos = m.jnt_qposadr[joint]
            self._finger_dof = m.jnt_dofadr[joint]
            self._finger_ctrl = m.actuator(self.finger_joint).id
            self._finger_velocity_ctrl = m.actuator(self.finger_joint + mjcf.VELOCITY_SUFFIX).id
            m.jnt_actfrclimited[joint] = 1
            gripper = self.figures['gripper']
            self.grip_force_range = (float(gripper['grip_force_min']), float(gripper['grip_force_max']))
            self.finger_tolerance = float(gripper['target_tolerance'])
            self._finger = dict(target=None, ramp=None, angle=None, speed=0.0,
                                force=self.grip_force_range[0], closing=False, stalled=0.0)

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
        self._reference = arm.copy()
        self._reference_velocity = np.zeros(len(arm))
        self._next_reference = arm.copy()
        self._hold_reference()
        if self.gripper is not None:
            opening = self.gripper.opening(d.qpos[self._finger_qpos])
            self._finger.update(target=opening, ramp=opening)
            self._drive_finger(0.0)
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
        return float(self.data.time)

    def step(self, dt):
        """Let `dt` seconds pass in whole timesteps (the remainder is carried over); returns how many."""
        self._debt += max(float(dt), 0.0)
        steps = int(math.floor(self._debt / self.timestep + 1e-9))
        self._debt -= steps * self.timestep
        start = self._reference
        change = self._next_reference - start
        moving = steps and change.any()
        # The servo's inertia feedforward: the torque that accelerating the arm along the reference
        # takes (mass matrix, armature included, times the reference's acceleration), given as an
        # offset of the position servo's reference.
        acceleration = None
        if steps and (self._reference_velocity != self._previous_velocity).any():
            acceleration = np.zeros(self.model.nv)
            acceleration[self._arm_dofs] = (self._reference_velocity - self._previous_velocity) / (
                steps * self.timestep)
            torque = np.zeros(self.model.nv)
        mujoco, model, data = self.mujoco, self.model, self.data
        ctrl, positions = self._ctrl, self._arm_position_ctrl
        ctrl[self._arm_velocity_ctrl] = self._reference_velocity
        # A protective stop already holding the arm keeps its hold reference for the whole call; one
        # tripped in a substep holds the arm from the next substep on.
        following = self.protective_stop is None
        for k in range(steps):
            if following:
                position = start + change * (float(k) / steps) if moving else start
                if acceleration is not None:
                    mujoco.mj_mulM(model, data, torque, acceleration)
                    position = position + torque[self._arm_dofs] / self._arm_kp
                ctrl[positions] = position
            if self.gripper is not None:
                self._drive_finger(self.timestep)
            mujoco.mj_step(model, data)
            if following:
                self._check_contact_force()
                following = self.protective_stop is None
            if self.gripper is not None:
                self._watch_finger()
        if steps and following:
            self._reference = self._next_reference.copy()
            self._previous_velocity = self._reference_velocity.copy()
        return steps

    # -- the arm ------------------------------------------------------------------

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
        self._next_reference = np.array(position, dtype=float)
        self._reference_velocity = np.array(velocity, dtype=float)

    def _set_arm_ctrl(self, position, velocity):
        self._ctrl[self._arm_position_ctrl] = position
        self._ctrl[self._arm_velocity_ctrl] = velocity

    def _hold_reference(self):
        """Hold the arm where it is now."""
        self._reference = self.arm_position
        self._next_reference = self._reference.copy()
        self._reference_velocity = np.zeros(len(self._reference))
        self._previous_velocity = self._reference_velocity.copy()
        self._set_arm_ctrl(self._reference, self._reference_velocity)

    def contact_force(self):
        """Net force (N, world frame) that the world's contacts put on the robot."""
        return self._cfrc_ext[self._robot_bodies, 3:].sum(axis=0)

    def _check_contact_force(self):
        force = self.contact_force()
        force = math.sqrt(force.dot(force))
        if force > self.protective_stop_force:
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

    # -- the 2F-140 ---------------------------------------------------------------

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
        state['stalled'] = 0.0

    def _rate(self, angle):
        return float(np.interp(angle, self.gripper.angles, self._rates))

    def _drive_finger(self, dt):
        ctrl, state = self._ctrl, self._finger
        ramp = state['ramp']
        if ramp != state['target'] or state['angle'] is None:
            step = state['speed'] * dt
            delta = state['target'] - ramp
            ramp = state['target'] if abs(delta) <= step else ramp + math.copysign(step, delta)
            angle = self.gripper.angle(ramp)
            ctrl[self._finger_velocity_ctrl] = (angle - ctrl[self._finger_ctrl]) / dt if dt > 0 else 0.0
            ctrl[self._finger_ctrl] = angle
            state.update(ramp=ramp, angle=angle)
        else:
            ctrl[self._finger_velocity_ctrl] = 0.0
        limit = state['force'] * self._rate(self._qpos[self._finger_qpos])
        self._actfrcrange[self._finger_joint, 0] = -limit
        self._actfrcrange[self._finger_joint, 1] = limit

    def _watch_finger(self):
        state = self._finger
        if abs(self._qvel[self._finger_dof]) < STALL_SPEED:
            state['stalled'] += self.timestep
        else:
            state['stalled'] = 0.0

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
