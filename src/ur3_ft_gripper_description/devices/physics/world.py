"""The world file of the physics cell: a table and the objects on it, checked field by field.

A world file is YAML (``config/worlds/default.yaml`` is one)::

    table:                      # optional: a fixed box
      size: [1.0, 1.2, 0.04]    # m, full extents along its x, y, z
      pose: [0.2, 0.0, -0.02]   # its centre: x y z (m), optionally roll pitch yaw (rad)
      friction: 0.5             # sliding friction coefficient
    objects:                    # optional: free bodies
      - name: box               # unique; the cell reports poses by it
        shape: box              # box, cylinder or mesh
        size: [0.05, 0.05, 0.12]  # box: x y z extents; cylinder: [diameter, height]
        pose: [0.3, -0.12, 0.06]  # its centre (box, cylinder) or its mesh's origin
        mass: 0.3               # kg
        friction: 0.6
      - name: part
        shape: mesh
        mesh: part.stl          # STL or OBJ, relative to the world file's folder
        scale: 0.001            # optional: a number or [sx, sy, sz] (default 1)
        pose: [0.35, 0.1, 0.0]
        mass: 0.2
        friction: 0.6

Poses are in the model's root frame (the robot's ``base_link``, z up): the
robot stands at its origin, on the table's top when that is at z = 0. An
object's inertia is MuJoCo's, from its shape at uniform density and the
given mass. Every problem is one ``WorldError`` line naming the file and the
field; objects inside the table, each other or the robot are found once the
cell is built (``Cell`` checks them with MuJoCo's own collision detection).
"""

import math
import os
import xml.etree.ElementTree as ElementTree

import yaml
from transforms3d.euler import euler2quat

from ur3_ft_gripper_description.number_text import number, number_list
from ur3_ft_gripper_description import yaml_data

SHAPES = ('box', 'cylinder', 'mesh')
MESH_FORMATS = ('.stl', '.obj')
TABLE_FIELDS = ('size', 'pose', 'friction')
OBJECT_FIELDS = ('name', 'shape', 'size', 'mesh', 'scale', 'pose', 'mass', 'friction')
TABLE_NAME = 'table'
# The other two friction coefficients of MuJoCo's contact (torsional and rolling, m): its defaults.
SPIN_AND_ROLL = (0.005, 0.0001)


class WorldError(ValueError):
    """A world file the cell cannot use; the message is one line naming the file and the field."""


class Solid(object):
    """The table or an object: a shape, its size, pose, mass (None: fixed) and friction."""

    def __init__(self, name, shape, size, position, quaternion, friction, mass=None, mesh=None,
                 scale=(1.0, 1.0, 1.0), label=None):
        self.name, self.shape, self.size = name, shape, size
        self.position, self.quaternion = position, quaternion
        self.friction, self.mass, self.mesh, self.scale = friction, mass, mesh, scale
        self.label = label or name  # how error lines name it: "objects[2] (can)"

    @property
    def fixed(self):
        return self.mass is None

    def half_sizes(self):
        """MuJoCo's size: half extents of a box, radius and half height of a cylinder."""
        if self.shape == 'box':
            return [s / 2.0 for s in self.size]
        if self.shape == 'cylinder':
            return [self.size[0] / 2.0, self.size[1] / 2.0]
        return []


class World(object):
    """A checked world: `table` (a Solid or None) and `objects` (Solids), from `path`."""

    def __init__(self, path, table, objects):
        self.path, self.table, self.objects = path, table, objects

    @property
    def solids(self):
        return ([self.table] if self.table is not None else []) + list(self.objects)

    def by_name(self, name):
        for solid in self.solids:
            if solid.name == name:
                return solid
        raise KeyError(name)

    def add_to_mjcf(self, root):
        """Add the table and the objects to an MJCF document (ElementTree root `mujoco`)."""
        asset = root.find('asset')
        if asset is None:
            asset = ElementTree.SubElement(root, 'asset')
        worldbody = root.find('worldbody')
        for solid in self.solids:
            geom = dict(name=solid.name, type=solid.shape,
                        friction=number_list((solid.friction,) + SPIN_AND_ROLL, ' '))
            if solid.shape == 'mesh':
                ElementTree.SubElement(asset, 'mesh', name=solid.name, file=solid.mesh,
                                       scale=number_list(solid.scale, ' '))
                geom['mesh'] = solid.name
            else:
                geom['size'] = number_list(solid.half_sizes(), ' ')
            pose = dict(pos=number_list(solid.position, ' '), quat=number_list(solid.quaternion, ' '))
            if solid.fixed:
                ElementTree.SubElement(worldbody, 'geom', dict(geom, **pose))
            else:
                body = ElementTree.SubElement(worldbody, 'body', dict(name=solid.name, **pose))
                ElementTree.SubElement(body, 'freejoint', name=solid.name)
                ElementTree.SubElement(body, 'geom', dict(geom, mass=number(solid.mass)))
        return root


def _finite(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


class _Reader(object):
    """Reads one entry (the table, objects[i]); its errors name the file and the entry."""

    def __init__(self, path, label, entry, fields):
        self.path, self.label, self.entry = path, label, entry
        if not isinstance(entry, dict):
            self.fail('must be a mapping of %s' % ', '.join(fields))
        unknown = sorted(set(entry) - set(fields))
        if unknown:
            self.fail("unknown field '%s' (the fields are %s)" % (unknown[0], ', '.join(fields)))

    def fail(self, problem):
        raise WorldError('%s: %s: %s' % (self.path, self.label, problem))

    def get(self, field, fix):
        if field not in self.entry:
            self.fail('no %s: %s' % (field, fix))
        return self.entry[field]

    def positive(self, field, fix):
        value = self.get(field, fix)
        if not _finite(value) or value <= 0:
            self.fail('%s=%r must be a number > 0 (%s)' % (field, value, fix))
        return float(value)

    def lengths(self, field, count, what):
        value = self.get(field, 'give %s' % what)
        if (not isinstance(value, list) or len(value) != count or
                not all(_finite(v) and v > 0 for v in value)):
            self.fail('%s=%r must be %s: %d numbers > 0 (m)' % (field, value, what, count))
        return [float(v) for v in value]

    def pose(self):
        value = self.get('pose', 'give x y z (m), and optionally roll pitch yaw (rad)')
        if not isinstance(value, list) or len(value) not in (3, 6) or not all(_finite(v) for v in value):
            self.fail('pose=%r must be x y z (m), optionally followed by roll pitch yaw (rad)' % (value,))
        value = [float(v) for v in value] + [0.0] * (6 - len(value))
        return value[:3], list(euler2quat(*value[3:], axes='sxyz'))


def _size(reader, shape):
    if shape == 'box':
        return reader.lengths('size', 3, 'the extents along x, y, z')
    return reader.lengths('size', 2, 'the diameter and the height')


def _mesh(reader, folder):
    value = reader.get('mesh', 'give the path of an STL or OBJ file')
    if not isinstance(value, str) or not value:
        reader.fail('mesh=%r must be the path of an STL or OBJ file' % (value,))
    path = os.path.normpath(os.path.join(folder, os.path.expanduser(value)))
    if not os.path.isfile(path):
        reader.fail('mesh %s does not exist (%s): give the path of an STL or OBJ file, relative to the '
                    "world file's folder" % (value, path))
    if os.path.splitext(path)[1].lower() not in MESH_FORMATS:
        reader.fail('mesh %s is not an STL or OBJ file, which MuJoCo reads: convert it (e.g. with trimesh)'
                    % value)
    scale = reader.entry.get('scale', 1.0)
    scale = [scale] * 3 if _finite(scale) else scale
    if not isinstance(scale, list) or len(scale) != 3 or not all(_finite(v) and v > 0 for v in scale):
        reader.fail('scale=%r must be a number > 0 or three of them' % (reader.entry.get('scale'),))
    return path, [float(v) for v in scale]


def _solid(path, label, entry, folder, movable):
    fields = OBJECT_FIELDS if movable else TABLE_FIELDS
    reader = _Reader(path, label, entry, fields)
    name = TABLE_NAME
    if movable:
        name = reader.get('name', 'give each object a name')
        if not isinstance(name, str) or not name.replace('_', 'a').isalnum():
            reader.fail('name=%r must be letters, digits and _' % (name,))
        label = '%s (%s)' % (label, name)
        reader.label = label
    shape = reader.entry.get('shape', 'box') if movable else 'box'
    if shape not in SHAPES:
        reader.fail("unknown shape '%s': use %s" % (shape, ', '.join(SHAPES)))
    mesh, scale, size = None, [1.0] * 3, None
    if shape == 'mesh':
        mesh, scale = _mesh(reader, folder)
        if 'size' in reader.entry:
            reader.fail("size is for boxes and cylinders: a mesh's size is its file's, times its scale")
    else:
        if 'mesh' in reader.entry or 'scale' in reader.entry:
            reader.fail('mesh and scale are for shape: mesh')
        size = _size(reader, shape)
    position, quaternion = reader.pose()
    friction = reader.positive('friction', 'give its sliding friction coefficient, e.g. 0.5')
    mass = reader.positive('mass', 'give its mass in kg') if movable else None
    return Solid(name, shape, size, position, quaternion, friction, mass, mesh, scale, label)


def load_world(path):
    """The World of the YAML file at `path`; WorldError (one line, naming the field) if it is bad."""
    try:
        with open(path) as f:
            data = yaml_data.load(f)
    except OSError as exc:
        raise WorldError('%s: cannot read the world file (%s): give the path of a world file, e.g. '
                         'config/worlds/default.yaml' % (path, exc.strerror or exc)) from None
    except yaml.YAMLError as exc:
        raise WorldError('%s: not YAML (%s)' % (path, ' '.join(str(exc).split()))) from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise WorldError('%s: a world file is a mapping with table and objects' % path)
    unknown = sorted(set(data) - {'table', 'objects'})
    if unknown:
        raise WorldError("%s: unknown section '%s' (a world file has table and objects)" % (path, unknown[0]))
    folder = os.path.dirname(os.path.abspath(path))
    table = None
    if data.get('table') is not None:
        table = _solid(path, 'table', data['table'], folder, movable=False)
    objects = data.get('objects') or []
    if not isinstance(objects, list):
        raise WorldError('%s: objects must be a list of objects' % path)
    solids = [_solid(path, 'objects[%d]' % i, entry, folder, movable=True) for i, entry in enumerate(objects)]
    taken = {TABLE_NAME}
    for solid in solids:
        if solid.name in taken:
            raise WorldError("%s: %s: the name '%s' is taken: give each object its own" % (
                path, solid.label, solid.name))
        taken.add(solid.name)
    return World(path, table, solids)


def empty_world():
    """A world without table and objects: the robot alone."""
    return World('(no world file)', None, [])


def overlap_problem(world, penetrations, tolerance):
    """The error line for the deepest overlap in `penetrations`, or None.

    `penetrations` holds (name, other name, depth in m) of every contact the
    cell's first collision pass found between the world's solids and between
    them and the robot (other name: the robot's link); depths up to
    `tolerance` are contact, not overlap.
    """
    deepest = max(penetrations, key=lambda p: p[2], default=None)
    if deepest is None or deepest[2] <= tolerance:
        return None
    names = {solid.name: solid for solid in world.solids}
    a, b, depth = deepest
    if a not in names:
        a, b = b, a
    solid, other = names[a], names.get(b)
    if solid.fixed and other is not None:
        solid, other = other, solid
    if other is None:
        what, fix = "the robot's %s at its start pose" % b, 'move the object or start the arm elsewhere'
    elif other.fixed:
        what, fix = 'the table', 'raise its pose z'
    else:
        what, fix = other.label, 'move one of them'
    return '%s: %s is inside %s (%.1f mm deep): %s' % (world.path, solid.label, what, depth * 1e3, fix)

