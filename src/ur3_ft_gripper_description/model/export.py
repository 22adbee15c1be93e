"""Flattened URDF for tools that do not speak ROS packages (simulators, URDF libraries).

``export_urdf`` expands the package's model with the chosen options through
the same checked pipeline as ``expand_description`` and can rewrite every
``package://`` mesh URI to a plain absolute path, resolved with rospkg: the
one form that MuJoCo, PyBullet, pinocchio, yourdfpy and libsdformat all open
(MuJoCo and PyBullet take a ``file://`` URI for a relative file name).
"""

import os

from ur3_ft_gripper_description.model import description
from ur3_ft_gripper_description.model.names import shared_rospack

PACKAGE_SCHEME = 'package://'
FILE_SCHEME = 'file://'


def model_mappings(ur_type='ur3', prefix='', ft_sensor=True, gripper=True, world=False,
                   joint_limit_params='', kinematics_params='', physical_params='', visual_params=''):
    """Top-level xacro args for one configuration (empty file = ur_type's default)."""
    return {
        'ur_type': ur_type, 'prefix': prefix,
        'ft_sensor': str(bool(ft_sensor)).lower(), 'gripper': str(bool(gripper)).lower(),
        'world': str(bool(world)).lower(),
        'joint_limit_params': joint_limit_params, 'kinematics_params': kinematics_params,
        'physical_params': physical_params, 'visual_params': visual_params,
    }


def mesh_elements(doc):
    return doc.documentElement.getElementsByTagName('mesh')


def resolve_uri(uri, rospack=None):
    """Local file path of a mesh URI (package://, file:// or a plain path)."""
    if uri.startswith(PACKAGE_SCHEME):
        package, _, relative = uri[len(PACKAGE_SCHEME):].partition('/')
        return os.path.join(description.package_path(package, rospack), relative)
    if uri.startswith(FILE_SCHEME):
        return uri[len(FILE_SCHEME):]
    return uri


def absolute_meshes(doc, rospack=None):
    """Rewrite every mesh URI to its absolute path; DescriptionError if a file is missing."""
    rospack = rospack or shared_rospack()
    for mesh in mesh_elements(doc):
        uri = mesh.getAttribute('filename')
        path = os.path.abspath(resolve_uri(uri, rospack))
        if not os.path.isfile(path):
            raise _missing_mesh(uri, path)
        mesh.setAttribute('filename', path)
    return doc


def _missing_mesh(uri, path):
    return description.DescriptionError(
        'mesh %s resolves to %s, which does not exist: reinstall the package that ships it' % (uri, path))


def export_urdf(mappings, absolute=False):
    """The flattened, checked URDF text of the package's model for `mappings`."""
    doc = description.expand_model(mappings)
    if absolute:
        absolute_meshes(doc)
    robot = doc.documentElement
    # Says what the file is; a comment may not contain '--', so no command line.
    options = ', '.join('%s=%s' % (k, mappings[k] or "''") for k in sorted(mappings))
    note = ' Exported by ur3_ft_gripper_description export_urdf (%s); meshes as %s. ' % (
        options, 'absolute paths' if absolute else 'package:// URIs')
    robot.insertBefore(doc.createComment(note), robot.firstChild)
    return description.to_xml(doc)
