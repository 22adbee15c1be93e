"""A MuJoCo model (MJCF) of the package's model, for ``export_mjcf``.

MuJoCo's own URDF import cannot take this model as it is: it reads no
``package://`` URIs, no DAE, drops ``<mimic>``, and the 2F-140's linkage,
a closed four-bar that URDF can only write as a tree, then collides with
itself. This writes the expanded model (with its inertials) as MJCF:

* every URDF link a body, every moving joint a hinge or slide with its range,
  damping and friction; fixed joints are bodies without a joint;
* every mimic joint an equality constraint on its leader's law
  (``joint1 = offset + multiplier * joint2``);
* the pairs that MoveIt's setup assistant finds Adjacent, colliding at the
  Default state or Always colliding (``config/collision_matrix.yaml``, the
  SRDF's source) excluded from contact: the linkage pins that touch at every
  opening, and parts joined across frames without geometry;
* collision meshes converted (trimesh) to binary STL beside the MJCF, scaled;
  they serve as the visual geometry too (MuJoCo has no DAE decoder);
* ``finger_joint`` driven by a position actuator, as the 2F-140's motor holds
  its fingers (ctrl 0 = open, up to its upper limit = closed), with a
  velocity gain beside it (``finger_joint_velocity``); the physics cell caps
  their torque at the grip force asked for.

What physics needs beyond the URDF (the figures and their sources are in
``config/physics.yaml``, read by ``load_physics_figures``):

* the solver: a 2 ms step, implicit integration of the servos' damping,
  elliptic friction cones, no fusing of fixed-joint bodies (the FT 300's
  frame must stay a body of its own for its sensor);
* every arm joint driven as the UR controller drives it: a position servo
  (actuator ``<joint>``, ctrl = the reference position) beside a velocity
  gain (``<joint>_velocity``, ctrl = the reference velocity), with an
  armature, gravity compensated through the actuators (``gravcomp`` on every
  body of the robot, ``actuatorgravcomp`` on the joints, as the controller
  compensates the arm and its configured payload), and the sum capped at
  the URDF's effort limit (``actuatorfrcrange``);
* the FT 300: a site at its sensor frame with a force and a torque sensor
  (``<frame>_force``, ``<frame>_torque``); MuJoCo reports there what the
  frame's parent exerts on it, i.e. minus what the tool side exerts on the
  sensor; and an accelerometer (``<frame>_accelerometer``), the specific
  force in the sensor frame as the FT 300's own reads it (at rest, gravity's
  reaction: 1 g up);
* the flange (``tool0``): the same pair of sensors, the wrench between the
  arm and everything mounted on it. An e-Series measures it there with its
  built-in sensor; a CB3 estimates it from its joint currents. The simulated
  robot's own ``wrench`` and ``get_tcp_force()`` start from it;
* the finger pads' friction and contact stiffness, and linkage equalities
  stiff enough that the closed four-bar does not drift.
"""

import math
import os
import re
from xml.dom import minidom

import numpy as np
import yaml
from transforms3d.quaternions import mat2quat

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.model import description, export
from ur3_ft_gripper_description.model.names import FINGER_JOINT, FLANGE, PADS
from ur3_ft_gripper_description.number_text import number, number_list
from ur3_ft_gripper_description import yaml_data

EXCLUDED_REASONS = ('Adjacent', 'Default', 'Always')
VELOCITY_SUFFIX = '_velocity'
FORCE_SUFFIX, TORQUE_SUFFIX, ACCELEROMETER_SUFFIX = '_force', '_torque', '_accelerometer'


def _config_path(name):
    return os.path.join(description.package_path('ur3_ft_gripper_description'), 'config', name)


def load_physics_figures(path=None):
    """The sections of config/physics.yaml (solver, arm, gripper) as dicts."""
    with open(path or _config_path('physics.yaml')) as f:
        figures = yaml_data.load(f)
    return {section: dict(figures[section]) for section in ('solver', 'arm', 'gripper')}


def ft_sensor_frame(path=None):
    """The FT 300's sensor frame (before the prefix): `sensor.frame_id` of config/sim_devices.yaml."""
    with open(path or _config_path('sim_devices.yaml')) as f:
        return yaml_data.load(f)['sensor']['frame_id']



def _numbers(values):
    return number_list((round(float(v), 12) + 0.0 for v in values), ' ')


def _pose_attributes(element, pose):
    """pos and quat of a urdf_parser_py Pose (None: identity) on an MJCF element."""
    matrix = kinematics.pose_matrix(pose)
    if np.any(matrix[:3, 3]):
        element.setAttribute('pos', _numbers(matrix[:3, 3]))
    if not np.allclose(matrix[:3, :3], np.eye(3)):
        element.setAttribute('quat', _numbers(mat2quat(matrix[:3, :3])))


def collision_matrix(mappings, path=None):
    """[[link, link, reason], ...] of config/collision_matrix.yaml for this configuration."""
    path = path or os.path.join(description.package_path('ur3_ft_gripper_description'), 'config',
                                'collision_matrix.yaml')
    with open(path) as f:
        table = yaml_data.load(f)['disable_collisions']
    parts = '_'.join(part for part in ('ft_sensor', 'gripper')
                     if mappings.get(part, 'true') == 'true') or 'arm'
    ur_type = mappings.get('ur_type', 'ur3')
    if ur_type not in table:
        raise description.DescriptionError(
            'config/collision_matrix.yaml has no entry for ur_type %s: run tools/generate_collision_matrix.py '
            '(see its docstring) for the installed ur_description' % ur_type)
    return table[ur_type][parts]


def _servo_joints(model, finger):
    """The arm's joints: every moving joint that no other joint mimics after, but the finger's."""
    return [joint.name for joint in model.robot.joints
            if joint.type in ('revolute', 'continuous', 'prismatic') and joint.mimic is None
            and joint.name != finger]


class MjcfWriter(object):
    def __init__(self, model, mesh_folder, prefix='', figures=None):
        self.model = model
        self.mesh_folder = mesh_folder
        self.doc = minidom.Document()
        self.meshes = {}  # (path, scale) -> asset name
        self.asset = self.doc.createElement('asset')
        self.figures = figures or load_physics_figures()
        self.finger = prefix + FINGER_JOINT
        self.arm_joints = _servo_joints(model, self.finger)
        self.pads = {prefix + pad for pad in PADS}
        self.ft_frame = prefix + ft_sensor_frame()
        self.flange = prefix + FLANGE

    def element(self, parent, tag, **attributes):
        node = self.doc.createElement(tag)
        for key, value in attributes.items():
            node.setAttribute(key, str(value))
        parent.appendChild(node)
        return node

    def mesh_asset(self, geometry):
        import trimesh
        path = os.path.abspath(export.resolve_uri(geometry.filename))
        scale = tuple(geometry.scale or (1.0, 1.0, 1.0))
        key = (path, scale)
        if key not in self.meshes:
            name = '%d_%s' % (len(self.meshes),
                              re.sub(r'[^A-Za-z0-9_]', '_', os.path.splitext(os.path.basename(path))[0]))
            mesh = trimesh.load(path, force='mesh')
            mesh.apply_scale(np.asarray(scale, dtype=float))
            out = os.path.join(self.mesh_folder, name + '.stl')
            mesh.export(out, file_type='stl')
            self.element(self.asset, 'mesh', name=name, file=out)
            self.meshes[key] = name
        return self.meshes[key]

    def body(self, parent, link_name, joint=None):
        link = self.model.robot.link_map[link_name]
        # The controller compensates the gravity of the arm and its configured payload (the tool).
        body = self.element(parent, 'body', name=link_name, gravcomp='1')
        if joint is not None:
            _pose_attributes(body, joint.origin)
            if joint.type in ('revolute', 'continuous', 'prismatic'):
                attributes = dict(name=joint.name, type='slide' if joint.type == 'prismatic' else 'hinge',
                                  axis=_numbers(joint.axis or (1.0, 0.0, 0.0)))
                if joint.type != 'continuous' and joint.limit is not None:
                    attributes['range'] = _numbers((joint.limit.lower, joint.limit.upper))
                    attributes['limited'] = 'true'
                if joint.dynamics is not None:
                    attributes['damping'] = number(joint.dynamics.damping or 0.0)
                    attributes['frictionloss'] = number(joint.dynamics.friction or 0.0)
                attributes.update(self.drive_attributes(joint))
                self.element(body, 'joint', **attributes)
        inertial = link.inertial
        if inertial is not None and inertial.mass > 0:
            i = inertial.inertia
            tensor = np.array([[i.ixx, i.ixy, i.ixz], [i.ixy, i.iyy, i.iyz], [i.ixz, i.iyz, i.izz]])
            pose = kinematics.pose_matrix(inertial.origin)
            tensor = pose[:3, :3].dot(tensor).dot(pose[:3, :3].T)  # into the body frame
            self.element(body, 'inertial', pos=_numbers(pose[:3, 3]), mass=number(inertial.mass),
                         fullinertia=_numbers([tensor[0, 0], tensor[1, 1], tensor[2, 2],
                                               tensor[0, 1], tensor[0, 2], tensor[1, 2]]))
        for k, collision in enumerate(link.collisions):
            geometry = collision.geometry
            attributes = dict(name='%s_collision_%d' % (link_name, k))
            if hasattr(geometry, 'filename'):
                attributes.update(type='mesh', mesh=self.mesh_asset(geometry))
            elif hasattr(geometry, 'size'):
                attributes.update(type='box', size=_numbers(np.asarray(geometry.size) / 2.0))
            elif hasattr(geometry, 'length'):
                attributes.update(type='cylinder', size=_numbers((geometry.radius, geometry.length / 2.0)))
            elif hasattr(geometry, 'radius'):
                attributes.update(type='sphere', size=number(geometry.radius))
            if link_name in self.pads:
                attributes.update(self.pad_attributes())
            geom = self.element(body, 'geom', **attributes)
            _pose_attributes(geom, collision.origin)
        if link_name in (self.ft_frame, self.flange):
            self.element(body, 'site', name=link_name)
        for child in self.model.robot.joints:
            if child.parent == link_name:
                self.body(body, child.child, child)
        return body

    def drive_attributes(self, joint):
        """What a joint's drive adds: an arm joint's armature, gravity compensation and effort limit."""
        if joint.name == self.finger:
            return dict(armature=number(self.figures['gripper']['finger_armature']))
        if joint.name not in self.arm_joints:
            return {}
        attributes = dict(armature=number(self.figures['arm']['armature']), actuatorgravcomp='true')
        if joint.limit is not None and joint.limit.effort:
            attributes['actuatorfrcrange'] = _numbers((-joint.limit.effort, joint.limit.effort))
        return attributes

    def pad_attributes(self):
        gripper = self.figures['gripper']
        return dict(friction=_numbers(gripper['pad_friction']), condim=str(int(gripper['pad_condim'])),
                    solref=_numbers(gripper['pad_solref']), solimp=_numbers(gripper['pad_solimp']),
                    priority='1')

    def option(self, root):
        solver = self.figures['solver']
        option = self.element(root, 'option', timestep=number(solver['timestep']),
                              integrator=solver['integrator'], cone=solver['cone'],
                              impratio=number(solver['impratio']),
                              noslip_iterations=str(int(solver['noslip_iterations'])))
        self.element(option, 'flag', **{name: 'enable' for name in solver.get('enable_flags', ())})

    def actuators(self, root):
        """Each arm joint's servo and the finger's: a position gain, and a velocity gain beside it."""
        actuator = self.element(root, 'actuator')
        arm = self.figures['arm']
        gains = []
        for name in self.arm_joints:
            kp = self.model.joints[name].limit.effort / float(arm['servo_error_at_effort_limit'])
            gains.append((name, kp, 2.0 * float(arm['servo_damping_ratio']) * math.sqrt(kp * float(arm['armature']))))
        # All position gains, then all velocity gains: each a contiguous block of ctrl for the cell.
        for name, kp, _ in gains:
            self.element(actuator, 'position', name=name, joint=name, kp=number(kp))
        for name, _, kv in gains:
            self.element(actuator, 'velocity', name=name + VELOCITY_SUFFIX, joint=name, kv=number(kv))
        if self.finger in self.model.joints:
            limit = self.model.joints[self.finger].limit
            gripper = self.figures['gripper']
            self.element(actuator, 'position', name=self.finger, joint=self.finger,
                         ctrlrange=_numbers((limit.lower, limit.upper)), kp=number(gripper['finger_kp']))
            self.element(actuator, 'velocity', name=self.finger + VELOCITY_SUFFIX, joint=self.finger,
                         kv=number(gripper['finger_kv']))

    def sensors(self, root):
        """Force and torque sensors at the flange and at the FT 300's sensor frame, and the FT 300's
        accelerometer."""
        frames = [frame for frame in (self.flange, self.ft_frame) if frame in self.model.robot.link_map]
        if frames:
            sensor = self.element(root, 'sensor')
        for frame in frames:
            self.element(sensor, 'force', name=frame + FORCE_SUFFIX, site=frame)
            self.element(sensor, 'torque', name=frame + TORQUE_SUFFIX, site=frame)
        if self.ft_frame in frames:
            self.element(sensor, 'accelerometer', name=self.ft_frame + ACCELEROMETER_SUFFIX, site=self.ft_frame)


def export_mjcf(mappings, output, matrix_path=None):
    """Write the MJCF of the package's model for `mappings` to `output`, meshes to <output>_meshes/."""
    return write_mjcf(description.expand_model(mappings), mappings, output, matrix_path)


def write_mjcf(doc, mappings, output, matrix_path=None, figures=None):
    """Write the MJCF of `doc`, the model expanded for `mappings`, to `output`; returns its text.

    `figures`: load_physics_figures()'s dict (default: config/physics.yaml's).
    """
    model = kinematics.Model(description.to_xml(doc))
    pairs = collision_matrix(mappings, matrix_path)
    stem = os.path.splitext(os.path.abspath(output))[0]
    mesh_folder = stem + '_meshes'
    try:
        os.makedirs(mesh_folder, exist_ok=True)
        with open(output, 'a'):
            pass
    except OSError as e:
        raise description.DescriptionError('cannot write %s (%s): give -o a file in a folder you can write' % (
            output, e.strerror or e)) from None
    prefix = mappings.get('prefix', '')
    writer = MjcfWriter(model, mesh_folder, prefix, figures)
    root = writer.element(writer.doc, 'mujoco', model=model.robot.name)
    # fusestatic off: the FT 300's sensor frame must stay a body of its own (MJCF's default, said).
    writer.element(root, 'compiler', angle='radian', autolimits='true', fusestatic='false')
    writer.option(root)
    root.appendChild(writer.asset)
    world = writer.element(root, 'worldbody')
    if model.root() == 'world':  # MuJoCo's own name for its world body: the model hangs from that
        for joint in model.robot.joints:
            if joint.parent == 'world':
                writer.body(world, joint.child, joint)
    else:
        writer.body(world, model.root())

    links = set(model.links)
    contact = writer.element(root, 'contact')
    for a, b, reason in pairs:
        if reason in EXCLUDED_REASONS and prefix + a in links and prefix + b in links:
            writer.element(contact, 'exclude', body1=prefix + a, body2=prefix + b)
    equality = writer.element(root, 'equality')
    linkage = writer.figures['gripper']
    for joint in model.robot.joints:
        if joint.mimic is not None:
            writer.element(equality, 'joint', name='%s_mimic' % joint.name, joint1=joint.name,
                           joint2=joint.mimic.joint, solref=_numbers(linkage['linkage_solref']),
                           solimp=_numbers(linkage['linkage_solimp']),
                           polycoef=_numbers((joint.mimic.offset or 0.0,
                                              1.0 if joint.mimic.multiplier is None
                                              else joint.mimic.multiplier,
                                              0, 0, 0)))
    writer.actuators(root)
    writer.sensors(root)
    options = ', '.join('%s=%s' % (k, mappings[k] or "''") for k in sorted(mappings))
    root.insertBefore(writer.doc.createComment(
        ' Exported by ur3_ft_gripper_description export_mjcf (%s); meshes in the folder beside this file. '
        % options),
        root.firstChild)
    text = writer.doc.toprettyxml(indent='  ')
    with open(output, 'w') as f:
        f.write(text)
    return text
