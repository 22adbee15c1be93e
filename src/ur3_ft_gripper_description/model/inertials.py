"""Mass properties a physics engine can trust, for the parts the upstream macros get wrong.

The upstream FT 300 macro gives its whole 300 g to ``ft300_sensor`` (centre
of mass outside the sensor body) and none to its coupling plate; the upstream
2F-140 links add up to 0.364 kg where Robotiq's manual says 0.975 kg; frames
without geometry (``base``, ``flange``, ``tool0``, ``robotiq_ft_frame_id``,
``gripper_tcp``) and the finger pads have no ``<inertial>`` at all, which
PyBullet fills with 1 kg each and libsdformat answers by dropping the links
below a preserved fixed joint. Frames get a negligible mass (``FRAME``).

How the figures are made (``tools/generate_link_inertials.py`` runs
``inertials_from_meshes``, which writes ``config/link_inertials.yaml``;
this module only reads that table, and needs no trimesh): each part
(FT 300, 2F-140) has a mass and a centre of mass along the flange axis from
the manual (``config/robotiq_mass.yaml``). Its links' collision meshes are
split into two groups of uniform density (FT 300: coupling plate | sensor
body; 2F-140: palm | fingers, knuckles and pads, with the gripper open); the
two densities are the ones that give both the manual's mass and its centre
of mass. Every link then gets its mesh's volume, centre of mass and inertia
tensor (trimesh's mass properties) at its group's density. Without the
FT 300 the gripper sits on Robotiq's coupling, whose mesh gets the density
of aluminium.

Which loading paths carry this: xacro cannot change an inertial that an
upstream macro has written, so ``apply`` runs in ``description.expand``:
``expand_description``, the launch files, ``export_urdf`` and ``export_mjcf``
have it; plain xacro on the top-level file does not (it has only the
coupling's inertial, which this package's macro writes itself).
"""

import os

import numpy as np

from ur3_ft_gripper_description.model.names import GRIPPER_BASE, child_elements, package_path
from ur3_ft_gripper_description.number_text import number, number_list
from ur3_ft_gripper_description import yaml_data

# Parts whose upstream inertials are replaced, by the link names the upstream
# macros give (before the prefix); the first link of each part anchors the prefix.
FT300_PLATE = 'ft300_mounting_plate'
FT300_BODY = 'ft300_sensor'
GRIPPER_PALM = GRIPPER_BASE
GRIPPER_MOVING = tuple('%s_%s' % (side, part) for side in ('left', 'right') for part in (
    'outer_knuckle', 'outer_finger', 'inner_finger', 'inner_finger_pad', 'inner_knuckle'))
PARTS = {
    'ft300': (FT300_BODY, FT300_PLATE),
    'gripper_2f_140': (GRIPPER_PALM,) + GRIPPER_MOVING,
}
INERTIA_KEYS = ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz')


def default_table_path():
    return os.path.join(package_path('ur3_ft_gripper_description'), 'config', 'link_inertials.yaml')


def load_table(path=None):
    with open(path or default_table_path()) as f:
        return yaml_data.load(f)['links']


def _inertial_element(doc, mass, com, inertia):
    inertial = doc.createElement('inertial')
    origin = doc.createElement('origin')
    origin.setAttribute('xyz', number_list(com, ' '))
    origin.setAttribute('rpy', '0 0 0')
    mass_element = doc.createElement('mass')
    mass_element.setAttribute('value', number(mass))
    inertia_element = doc.createElement('inertia')
    for key in INERTIA_KEYS:
        inertia_element.setAttribute(key, number(inertia[key]))
    for child in (origin, mass_element, inertia_element):
        inertial.appendChild(child)
    return inertial


def _set_inertial(doc, link, entry):
    for old in child_elements(link, 'inertial'):
        link.removeChild(old)
    link.insertBefore(_inertial_element(doc, entry['mass'], entry['com'], entry['inertia']), link.firstChild)


def mass_below(model, frame, positions=None):
    """(mass, centre of mass in `frame`) of every link below `frame` in a kinematics.Model.

    What a force-torque sensor whose measuring frame is `frame` carries; joints
    at `positions` (default 0: the 2F-140 open). (0, origin) when nothing hangs there.
    """
    if frame not in model.links:
        raise ValueError('the model has no link %s' % frame)
    parts = []
    for link in model.links:
        inertial = model.robot.link_map[link].inertial
        if link == frame or inertial is None or frame not in _ancestors(model, link):
            continue
        pose = model.transform(frame, link, positions)
        centre = pose[:3, :3].dot(inertial.origin.xyz if inertial.origin else (0.0, 0.0, 0.0)) + pose[:3, 3]
        parts.append((inertial.mass, centre))
    return combine_masses(parts)


def combine_masses(parts):
    """Total mass and common centre of mass of [(mass, com), ...]; (0, origin) for no mass."""
    total = 0.0
    moment = np.zeros(3)
    for mass, com in parts:
        mass = float(mass)
        if not np.isfinite(mass) or mass < 0:
            raise ValueError('a mass must be a finite number >= 0, got %r' % mass)
        com = np.asarray(com, dtype=float).reshape(-1)
        if com.shape != (3,) or not np.all(np.isfinite(com)):
            raise ValueError('a centre of mass must be 3 finite numbers, got %r' % (com,))
        total += mass
        moment += mass * com
    if total == 0.0:
        return 0.0, np.zeros(3)
    return total, moment / total


def _ancestors(model, link):
    names = []
    while link in model.parent_joint:
        link = model.parent_joint[link].parent
        names.append(link)
    return names


# What a frame without geometry weighs: 10 mg, as a sphere of 1 mm radius
# (I = 2/5 m r^2). Not zero: libsdformat 12 takes any mass within 1e-6 kg of
# zero for no inertial and then drops the links below a preserved fixed joint
# (or divides by the lumped mass, zero, and rejects the model); not absent:
# PyBullet puts 1 kg on a link without <inertial>. Ten frames add 0.1 g to a
# 12 kg model.
FRAME = {'mass': 1e-5, 'com': (0.0, 0.0, 0.0),
         'inertia': dict(ixx=4e-12, ixy=0.0, ixz=0.0, iyy=4e-12, iyz=0.0, izz=4e-12)}


def apply(doc, table=None):
    """Give the model's FT 300 and 2F-140 links their inertials and every bare frame a negligible one.

    A part is recognised by all its upstream link names under one prefix.
    A non-root link with neither geometry nor inertial is a frame: it gets
    ``FRAME``, so that no engine puts its default mass there. The root keeps
    none (KDL, under robot_state_publisher, warns about an inertial on the
    root, and a fixed-base engine never moves it). Returns the names of the
    links changed.
    """
    robot = doc.documentElement
    links = {link.getAttribute('name'): link for link in child_elements(robot, 'link')}
    children = {c.getAttribute('link') for j in child_elements(robot, 'joint') for c in child_elements(j, 'child')}
    changed = []
    if any(name.endswith(part[0]) for name in links for part in PARTS.values()):
        table = table if table is not None else load_table()
        for part in PARTS.values():
            anchor = part[0]
            for name in list(links):
                if not name.endswith(anchor):
                    continue
                prefix = name[:-len(anchor)]
                if all(prefix + n in links for n in part):
                    for n in part:
                        _set_inertial(doc, links[prefix + n], table[n])
                        changed.append(prefix + n)
    for name, link in links.items():
        if name in children and not any(child_elements(link, tag) for tag in ('inertial', 'visual', 'collision')):
            _set_inertial(doc, link, FRAME)
            changed.append(name)
    return changed
