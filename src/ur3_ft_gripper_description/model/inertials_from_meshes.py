"""config/link_inertials.yaml from the collision meshes and the manual's figures (needs trimesh).

What ``tools/generate_link_inertials.py`` runs; ``inertials`` applies the
stored table when the model is expanded and its docstring says how the
figures are made. This module sits above the expansion (it expands the
model to measure it), so the expansion never loads it or trimesh.
"""

import numpy as np
import yaml

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.model import description, export
from ur3_ft_gripper_description.model.inertials import (FT300_BODY, FT300_PLATE, GRIPPER_MOVING, GRIPPER_PALM,
                                                        INERTIA_KEYS, PARTS)

# Robotiq's coupling (the gripper's mount without the FT 300): its inertial is
# written by this package's macro from the table, not replaced at expand time.
COUPLING = 'robotiq_arg2f_coupling'


class VolumeProperties(object):
    """Volume (m^3), centre of volume (m) and inertia at unit density about it, in a link frame."""

    def __init__(self, volume, centre, unit_inertia):
        self.volume = float(volume)
        self.centre = np.asarray(centre, dtype=float)
        self.unit_inertia = np.asarray(unit_inertia, dtype=float)


def _collision_mesh(collision, resolve):
    import trimesh
    geometry = collision.geometry
    if hasattr(geometry, 'filename'):
        mesh = trimesh.load(resolve(geometry.filename), force='mesh')
        if geometry.scale:
            mesh.apply_scale(np.asarray(geometry.scale, dtype=float))
    elif hasattr(geometry, 'size'):
        mesh = trimesh.creation.box(extents=geometry.size)
    else:
        raise ValueError('collision geometry %s has no mass properties here' % type(geometry).__name__)
    mesh.apply_transform(kinematics.pose_matrix(collision.origin))
    if not mesh.is_watertight:
        raise ValueError('collision mesh %s is not watertight: its volume is undefined' % geometry)
    return mesh


def volume_properties(link, resolve):
    """VolumeProperties of a urdf_parser_py link's collision geometry (`resolve`: mesh URI -> path)."""
    import trimesh
    meshes = [_collision_mesh(c, resolve) for c in link.collisions]
    if not meshes:
        raise ValueError('link %s has no collision geometry' % link.name)
    mesh = trimesh.util.concatenate(meshes) if len(meshes) > 1 else meshes[0]
    mesh.density = 1.0
    return VolumeProperties(mesh.volume, mesh.center_mass, mesh.moment_inertia)


def two_densities(group_a, group_b, mass, com_z):
    """Densities (kg/m^3) of two groups that give `mass` and the centre of mass height `com_z`.

    Each group is a list of (volume, centre z) in one common frame. ValueError
    when no pair of positive densities does it (the COM lies outside the span
    of the two groups' centres).
    """
    volume_a, volume_b = (sum(v for v, _ in g) for g in (group_a, group_b))
    z_a, z_b = (sum(v * z for v, z in g) / sum(v for v, _ in g) for g in (group_a, group_b))
    mass_b = mass * (com_z - z_a) / (z_b - z_a)
    mass_a = mass - mass_b
    if mass_a <= 0 or mass_b <= 0:
        raise ValueError('a centre of mass at z = %.4f m cannot be made from groups centred at '
                         '%.4f and %.4f m with positive densities' % (com_z, z_a, z_b))
    return mass_a / volume_a, mass_b / volume_b


def link_entry(props, density):
    """The YAML entry of one link: mass, com and inertia about the com (link frame)."""
    inertia = props.unit_inertia * density
    return {
        'mass': round(props.volume * density, 9),
        'com': [round(float(v), 9) + 0.0 for v in props.centre],
        'inertia': dict(zip(INERTIA_KEYS, (round(float(inertia[i, j]), 12) + 0.0 for i, j in (
            (0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))))),
    }


def distribute(full_model, coupling_model, figures, resolve):
    """Per-link entries and the densities used, from expanded models (kinematics.Model).

    `full_model` has the FT 300 and the gripper (gripper open: finger_joint 0),
    `coupling_model` the gripper on the coupling; `figures` is robotiq_mass.yaml.
    """
    links = {}
    densities = {}

    def props(model, name):
        return volume_properties(model.robot.link_map[name], resolve)

    def centre_z(model, name, p):
        t = model.transform('tool0', name)
        return float(t[:3, :3].dot(p.centre)[2] + t[2, 3])

    # FT 300: coupling plate | sensor body, to the manual's "FT 300 alone".
    ft = {name: props(full_model, name) for name in PARTS['ft300']}
    plate, body = two_densities(
        [(ft[FT300_PLATE].volume, centre_z(full_model, FT300_PLATE, ft[FT300_PLATE]))],
        [(ft[FT300_BODY].volume, centre_z(full_model, FT300_BODY, ft[FT300_BODY]))],
        figures['ft300']['mass'], figures['ft300']['com_z_from_tool0'])
    densities.update({FT300_PLATE: plate, FT300_BODY: body})

    # 2F-140: what the manual's FT 300 + 2F-140 adds to the FT 300 alone.
    alone, both = figures['ft300'], figures['ft300_with_2f140']
    gripper_mass = both['mass'] - alone['mass']
    gripper_com_z = (both['mass'] * both['com_z_from_tool0']
                     - alone['mass'] * alone['com_z_from_tool0']) / gripper_mass
    grip = {name: props(full_model, name) for name in PARTS['gripper_2f_140']}
    palm, fingers = two_densities(
        [(grip[GRIPPER_PALM].volume, centre_z(full_model, GRIPPER_PALM, grip[GRIPPER_PALM]))],
        [(grip[n].volume, centre_z(full_model, n, grip[n])) for n in GRIPPER_MOVING],
        gripper_mass, gripper_com_z)
    densities.update({GRIPPER_PALM: palm})
    densities.update({name: fingers for name in GRIPPER_MOVING})

    for name, p in list(ft.items()) + list(grip.items()):
        links[name] = link_entry(p, densities[name])
    densities[COUPLING] = float(figures['coupling_density'])
    links[COUPLING] = link_entry(props(coupling_model, COUPLING), densities[COUPLING])
    return links, densities


HEADER = '''\
# GENERATED by tools/generate_link_inertials.py (run it in `bash tools/quickstart shell`); do not edit.
# <inertial> of the FT 300, 2F-140 and coupling links (kg, m, kg m^2; com and
# inertia about the com in the link frame), made from config/robotiq_mass.yaml
# and the collision meshes by ur3_ft_gripper_description.model.inertials (its
# docstring says how). Densities that give the manual's masses and centres of
# mass (kg/m^3):
'''


def compute_table(figures):
    """distribute() over the default model with and without the FT 300: what the stored table holds."""
    def expanded(**options):
        return kinematics.Model(description.to_xml(description.expand_model(export.model_mappings(**options))))
    return distribute(expanded(), expanded(ft_sensor=False), figures, export.resolve_uri)


def write_yaml(path, links, densities):
    lines = [HEADER]
    lines.extend('#   %s: %.0f\n' % (name, densities[name]) for name in sorted(densities))
    with open(path, 'w') as f:
        f.writelines(lines)
        yaml.safe_dump({'links': links}, f, default_flow_style=None, sort_keys=True)
