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
  its fingers (ctrl 0 = open, up to its upper limit = closed).
"""

import os
import re
from xml.dom import minidom

import numpy as np
import yaml
from transforms3d.quaternions import mat2quat

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.model import description, export
from ur3_ft_gripper_description.model.names import FINGER_JOINT

EXCLUDED_REASONS = ('Adjacent', 'Default', 'Always')
MIMIC_SOLREF = '0.005 1'  # stiffer than MuJoCo's default 0.02 s: the linkage must not drift
FINGER_ACTUATOR = dict(kp='20', kv='0.5', forcerange='-20 20')


def _numbers(values):
    return ' '.join(repr(round(float(v), 12) + 0.0) for v in values)


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
        table = yaml.safe_load(f)['disable_collisions']
    parts = '_'.join(part for part in ('ft_sensor', 'gripper')
                     if mappings.get(part, 'true') == 'true') or 'arm'
    ur_type = mappings.get('ur_type', 'ur3')
    if ur_type not in table:
        raise description.DescriptionError(
            'config/collision_matrix.yaml has no entry for ur_type %s: run tools/generate_collision_matrix.py '
            '(see its docstring) for the installed ur_description' % ur_type)
    return table[ur_type][parts]


class MjcfWriter(object):
    def __init__(self, model, mesh_folder):
        self.model = model
        self.mesh_folder = mesh_folder
        self.doc = minidom.Document()
        self.meshes = {}  # (path, scale) -> asset name
        self.asset = self.doc.createElement('asset')

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
        body = self.element(parent, 'body', name=link_name)
        if joint is not None:
            _pose_attributes(body, joint.origin)
            if joint.type in ('revolute', 'continuous', 'prismatic'):
                attributes = dict(name=joint.name, type='slide' if joint.type == 'prismatic' else 'hinge',
                                  axis=_numbers(joint.axis or (1.0, 0.0, 0.0)))
                if joint.type != 'continuous' and joint.limit is not None:
                    attributes['range'] = _numbers((joint.limit.lower, joint.limit.upper))
                    attributes['limited'] = 'true'
                if joint.dynamics is not None:
                    attributes['damping'] = repr(float(joint.dynamics.damping or 0.0))
                    attributes['frictionloss'] = repr(float(joint.dynamics.friction or 0.0))
                self.element(body, 'joint', **attributes)
        inertial = link.inertial
        if inertial is not None and inertial.mass > 0:
            i = inertial.inertia
            tensor = np.array([[i.ixx, i.ixy, i.ixz], [i.ixy, i.iyy, i.iyz], [i.ixz, i.iyz, i.izz]])
            pose = kinematics.pose_matrix(inertial.origin)
            tensor = pose[:3, :3].dot(tensor).dot(pose[:3, :3].T)  # into the body frame
            self.element(body, 'inertial', pos=_numbers(pose[:3, 3]), mass=repr(float(inertial.mass)),
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
                attributes.update(type='sphere', size=repr(float(geometry.radius)))
            geom = self.element(body, 'geom', **attributes)
            _pose_attributes(geom, collision.origin)
        for child in self.model.robot.joints:
            if child.parent == link_name:
                self.body(body, child.child, child)
        return body


def export_mjcf(mappings, output, matrix_path=None):
    """Write the MJCF of the package's model for `mappings` to `output`, meshes to <output>_meshes/."""
    doc = description.expand_model(mappings)
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
    writer = MjcfWriter(model, mesh_folder)
    root = writer.element(writer.doc, 'mujoco', model=model.robot.name)
    writer.element(root, 'compiler', angle='radian', autolimits='true')
    root.appendChild(writer.asset)
    world = writer.element(root, 'worldbody')
    if model.root() == 'world':  # MuJoCo's own name for its world body: the model hangs from that
        for joint in model.robot.joints:
            if joint.parent == 'world':
                writer.body(world, joint.child, joint)
    else:
        writer.body(world, model.root())

    prefix = mappings.get('prefix', '')
    links = set(model.links)
    contact = writer.element(root, 'contact')
    for a, b, reason in pairs:
        if reason in EXCLUDED_REASONS and prefix + a in links and prefix + b in links:
            writer.element(contact, 'exclude', body1=prefix + a, body2=prefix + b)
    equality = writer.element(root, 'equality')
    for joint in model.robot.joints:
        if joint.mimic is not None:
            writer.element(equality, 'joint', name='%s_mimic' % joint.name, joint1=joint.name,
                           joint2=joint.mimic.joint, solref=MIMIC_SOLREF,
                           polycoef=_numbers((joint.mimic.offset or 0.0,
                                              1.0 if joint.mimic.multiplier is None
                                              else joint.mimic.multiplier,
                                              0, 0, 0)))
    finger = prefix + FINGER_JOINT
    if finger in model.joints:
        actuator = writer.element(root, 'actuator')
        limit = model.joints[finger].limit
        writer.element(actuator, 'position', name=finger, joint=finger,
                       ctrlrange=_numbers((limit.lower, limit.upper)), **FINGER_ACTUATOR)
    options = ', '.join('%s=%s' % (k, mappings[k] or "''") for k in sorted(mappings))
    root.insertBefore(writer.doc.createComment(
        ' Exported by ur3_ft_gripper_description export_mjcf (%s); meshes in the folder beside this file. '
        % options),
        root.firstChild)
    text = writer.doc.toprettyxml(indent='  ')
    with open(output, 'w') as f:
        f.write(text)
    return text
