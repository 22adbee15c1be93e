"""Expand xacro into a checked URDF, with one-line errors for bad input.

This is the engine behind `expand_description` (a drop-in for the xacro
command) and the launch files. It runs the real xacro on the real upstream
files and then:

* removes the extra ``<prefix>base_link`` and its joint that the jr-robotics
  Noetic fork of the 2F-140 macro emits (they collide with the arm's root);
* refuses to return a model that is not one tree (duplicate names, dangling
  joints, several roots), so that ``robot_description`` is never half-built;
* gives the FT 300 and 2F-140 links the manufacturer's mass properties and
  every bare frame a negligible one (``inertials``), and writes the
  transmissions' hardware interfaces as ros_control names them.
"""

import os
import re
import subprocess

import yaml

from ur3_ft_gripper_description.model import inertials

# Package -> how a user gets it; used in "package not found" errors.
PACKAGE_SOURCES = {
    'ur_description': 'sudo apt install ros-noetic-ur-description, or clone '
                      'ros-industrial/universal_robot (see repos/robotiq-noetic.repos)',
    'robotiq_ft_sensor': 'clone ros-industrial/robotiq or jr-robotics/robotiq into your '
                         'catkin workspace (see repos/robotiq-noetic.repos)',
    'robotiq_2f_140_gripper_visualization': 'clone ros-industrial/robotiq or jr-robotics/robotiq '
                                            'into your catkin workspace '
                                            '(see repos/robotiq-noetic.repos)',
}
MODEL_PACKAGES = ('ur_description', 'robotiq_ft_sensor', 'robotiq_2f_140_gripper_visualization')

# Names both upstream 2F-140 macros give (before the prefix).
GRIPPER_BASE = 'robotiq_arg2f_base_link'
FINGER_JOINT = 'finger_joint'
PADS = ('left_inner_finger_pad', 'right_inner_finger_pad')

# Top-level xacro args that name UR parameter files, with the keys the UR
# macro reads from each (ur_description/urdf/inc/ur_common.xacro).
UR_JOINTS = ('shoulder_pan', 'shoulder_lift', 'elbow_joint', 'wrist_1', 'wrist_2', 'wrist_3')
UR_KINEMATIC_SEGMENTS = ('shoulder', 'upper_arm', 'forearm', 'wrist_1', 'wrist_2', 'wrist_3')
# The file in ur_description/config/<ur_type>/ that each arg defaults to (in the macro).
UR_DEFAULT_FILES = {
    'joint_limit_params': 'joint_limits.yaml',
    'kinematics_params': 'default_kinematics.yaml',
    'physical_params': 'physical_parameters.yaml',
    'visual_params': 'visual_parameters.yaml',
}
PARAMETER_FILE_ARGS = {
    'joint_limit_params': ('joint_limits', UR_JOINTS),
    'kinematics_params': ('kinematics', UR_KINEMATIC_SEGMENTS),
    'physical_params': ('dh_parameters', ()),
    'visual_params': ('mesh_files', ()),
}


# Top-level xacro args that must be true or false.
BOOLEAN_ARGS = ('ft_sensor', 'gripper', 'world', 'safety_limits')
BOOLEAN_VALUES = ('true', 'false', 'True', 'False', '1', '0')

# A TF frame name: segments of letters, digits and '_', separated by '/'.
FRAME_NAME = re.compile(r'^[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$')


class _ParameterFileLoader(yaml.SafeLoader):
    """YAML as xacro.load_yaml reads it: ur_description's limits use !degrees."""


_ParameterFileLoader.add_constructor(
    '!degrees', lambda loader, node: float(loader.construct_scalar(node)) * 3.141592653589793 / 180.0)
_ParameterFileLoader.add_constructor(
    '!radians', lambda loader, node: float(loader.construct_scalar(node)))


class DescriptionError(Exception):
    """Bad input or environment; the message is one line naming problem and fix."""


def check_prefix(prefix):
    """A prefix must turn every link name into a valid TF frame name."""
    if prefix and not FRAME_NAME.match(prefix + 'base_link'):
        raise DescriptionError(
            "prefix %r cannot start a TF frame name: use letters, digits, '_' and '/' "
            "(not first), e.g. prefix:=left_ or prefix:=robot1/" % prefix)


def ur_types(rospack=None):
    """The UR models the installed ur_description ships, in its own order (ur3, ur3e, ur5, ...).

    A model is a folder of ur_description/config with the four default
    parameter files that the macro picks for ur_type.
    """
    config = os.path.join(package_path('ur_description', rospack), 'config')
    models = [name for name in os.listdir(config)
              if all(os.path.isfile(os.path.join(config, name, f)) for f in UR_DEFAULT_FILES.values())]
    return sorted(models, key=lambda name: [int(part) if part.isdigit() else part
                                            for part in re.split(r'(\d+)', name)])


def unknown_ur_type_error(ur_type, rospack=None):
    return DescriptionError(
        "ur_type %r is not a UR model that the installed ur_description ships: use one of %s"
        % (ur_type, ', '.join(ur_types(rospack))))


def check_ur_type(ur_type):
    if ur_type not in ur_types():
        raise unknown_ur_type_error(ur_type)


def check_boolean(arg, value):
    if str(value) not in BOOLEAN_VALUES:
        raise DescriptionError('%s:=%r is not a boolean: use %s:=true or %s:=false' % (
            arg, value, arg, arg))


def _rospack():
    import rospkg
    return rospkg.RosPack()


def package_path(name, rospack=None):
    """Path of ROS package `name`, or DescriptionError saying how to get it."""
    import rospkg
    try:
        return (rospack or _rospack()).get_path(name)
    except rospkg.ResourceNotFound:
        how = PACKAGE_SOURCES.get(name, 'install it or add its folder to ROS_PACKAGE_PATH')
        raise DescriptionError(
            "ROS package '%s' not found on ROS_PACKAGE_PATH: %s" % (name, how)) from None


def check_model_packages():
    """Fail early and clearly if an upstream package of the model is missing."""
    rospack = _rospack()
    for name in MODEL_PACKAGES:
        package_path(name, rospack)
    urdf_dir = os.path.join(package_path('robotiq_2f_140_gripper_visualization', rospack), 'urdf')
    if not any(os.path.isfile(os.path.join(urdf_dir, f)) for f in
               ('robotiq_arg2f_140_model_macro.xacro', 'robotiq_arg2f_140_macro.xacro')):
        raise DescriptionError(
            "no 2F-140 macro (robotiq_arg2f_140_model_macro.xacro or robotiq_arg2f_140_macro.xacro) "
            "in %s: use the ros-industrial/robotiq or jr-robotics/robotiq package" % urdf_dir)


def check_parameter_file(arg, path):
    """Check one UR parameter file before xacro reads it."""
    if arg not in PARAMETER_FILE_ARGS or path == '':
        return
    section, required = PARAMETER_FILE_ARGS[arg]
    fix = 'give %s:=<path to a YAML file like ur_description/config/ur3/%s>' % (
        arg, UR_DEFAULT_FILES[arg])
    if not os.path.isfile(path):
        raise DescriptionError('%s: file not found: %s; %s' % (arg, path, fix))
    try:
        with open(path) as f:
            data = yaml.load(f, Loader=_ParameterFileLoader)
    except yaml.YAMLError as e:
        where = getattr(e, 'problem_mark', None)
        line = ' (line %d)' % (where.line + 1) if where else ''
        raise DescriptionError('%s: %s is not valid YAML%s; %s' % (arg, path, line, fix)) from None
    if data is None:
        raise DescriptionError('%s: %s is empty; %s' % (arg, path, fix))
    if not isinstance(data, dict) or section not in data:
        raise DescriptionError("%s: %s has no '%s' section; %s" % (arg, path, section, fix))
    missing = [k for k in required if k not in (data[section] or {})]
    if missing:
        raise DescriptionError("%s: %s has no entry for %s in '%s'; %s" % (
            arg, path, ', '.join(missing), section, fix))


def load_xacro():
    """The ROS 1 xacro module; its `$(find pkg)` goes through roslaunch and ROS_PACKAGE_PATH."""
    try:
        import xacro
    except ImportError:
        raise DescriptionError(
            'xacro is not installed: sudo apt install ros-noetic-xacro, or build ros/xacro '
            '(noetic-devel) in your catkin workspace and source it') from None
    if not hasattr(xacro, 'load_yaml'):
        raise DescriptionError(
            'this xacro has no xacro.load_yaml, which ur_description needs: install '
            'ros-noetic-xacro >= 1.14.10')
    return xacro


def _causes(exc):
    """`exc` and the exceptions behind it (xacro wraps them in XacroException.exc)."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        yield exc
        seen.add(id(exc))
        exc = getattr(exc, 'exc', None) or exc.__cause__ or exc.__context__


def _explain(exc):
    """The one-line DescriptionError for a xacro failure whose cause we know, else None."""
    for cause in _causes(exc):
        if isinstance(cause, DescriptionError):
            return cause
        if isinstance(cause, FileNotFoundError) and cause.filename:
            # The macro's default parameter file of a ur_type that ur_description lacks.
            folder, name = os.path.split(os.path.realpath(cause.filename))
            config = os.path.realpath(os.path.join(package_path('ur_description'), 'config'))
            model = os.path.basename(folder)
            if (os.path.dirname(folder) == config and name in UR_DEFAULT_FILES.values()
                    and model not in ur_types()):
                return unknown_ur_type_error(model)
    return None


def run_xacro(xacro_file, mappings=None):
    """Run xacro on `xacro_file`; returns the minidom document."""
    mappings = dict(mappings or {})
    if not os.path.isfile(xacro_file):
        raise DescriptionError('xacro file not found: %s' % xacro_file)
    for arg, value in mappings.items():
        check_parameter_file(arg, value)
    check_prefix(mappings.get('prefix', ''))
    xacro = load_xacro()
    try:
        return xacro.process_file(xacro_file, mappings=mappings)
    except Exception as e:  # xacro raises many types; all become one line
        known = _explain(e)
        if known is not None:
            raise known from None
        text = ' '.join(str(e).split()) or type(e).__name__
        raise DescriptionError('xacro failed on %s: %s' % (xacro_file, text)) from None


def _elements(robot, tag):
    return [n for n in robot.childNodes if n.nodeType == n.ELEMENT_NODE and n.tagName == tag]


def _link_of(joint, tag):
    nodes = joint.getElementsByTagName(tag)
    return nodes[0].getAttribute('link') if nodes else ''


def remove_forked_gripper_roots(doc):
    """Drop the jr-robotics fork's `<p>base_link` -> `<p>robotiq_arg2f_base_link` joint.

    Only when the gripper base also has another parent (it is mounted on
    something), so a stand-alone gripper keeps its root. The link goes too
    when it is a second definition of the name or nothing else uses it.
    Returns the names of the removed joints.
    """
    robot = doc.documentElement
    joints = _elements(robot, 'joint')
    parents_of = {}
    for joint in joints:
        parents_of.setdefault(_link_of(joint, 'child'), []).append(joint)
    removed = []
    for joint in joints:
        parent, child = _link_of(joint, 'parent'), _link_of(joint, 'child')
        if not child.endswith(GRIPPER_BASE):
            continue
        prefix = child[:-len(GRIPPER_BASE)]
        is_fork_root = (parent == prefix + 'base_link' and
                        joint.getAttribute('name') == '%s-%s' % (parent, child))
        if not is_fork_root or len(parents_of[child]) < 2:
            continue
        robot.removeChild(joint)
        removed.append(joint.getAttribute('name'))
        same_name = [lk for lk in _elements(robot, 'link') if lk.getAttribute('name') == parent]
        still_used = any(parent in (_link_of(j, 'parent'), _link_of(j, 'child'))
                         for j in _elements(robot, 'joint'))
        empty = [lk for lk in same_name if not any(
            c.nodeType == c.ELEMENT_NODE for c in lk.childNodes)]
        if empty and (len(same_name) > 1 or not still_used):
            robot.removeChild(empty[-1])  # the fork's comes after the arm's
    return removed


def check_tree(doc):
    """Raise DescriptionError unless the URDF is one tree with unique, TF-valid names.

    The tree is urdfdom's to judge (check_urdf): it is the parser
    robot_state_publisher and RViz load the model with.
    """
    try:
        run = subprocess.run(['check_urdf', '/dev/stdin'], input=to_xml(doc), universal_newlines=True,
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    except FileNotFoundError:
        raise DescriptionError('check_urdf is not installed: sudo apt install liburdfdom-tools') from None
    if run.returncode != 0:
        errors = [line.split(':', 1)[1].strip() for line in run.stdout.splitlines()
                  if line.startswith('Error:')]
        reason = errors[0] if errors else ' '.join(run.stdout.split())
        fix = ('give each robot its own prefix' if 'not unique' in reason else
               'every link must hang from one root link through exactly one joint')
        raise DescriptionError('the expanded model is not one URDF tree: %s (check_urdf); %s' % (
            reason, fix))
    # urdfdom accepts link names that tf2 cannot take as frame ids.
    for link in _elements(doc.documentElement, 'link'):
        name = link.getAttribute('name')
        if not FRAME_NAME.match(name):
            raise DescriptionError(
                "link name %r is not a valid TF frame name: use letters, digits, '_' and '/'" % name)


def fix_transmission_interfaces(doc):
    """Write every ros_control hardware interface as its full class name.

    The jr-robotics 2F-140 macro passes on ``hardware/interface/EffortJointInterface``
    and ros-industrial's a bare ``PositionJointInterface``; ros_control's
    plugin loader knows them as ``hardware_interface/<Name>``.
    Returns the names it changed.
    """
    changed = []
    for element in doc.documentElement.getElementsByTagName('hardwareInterface'):
        text = ''.join(n.data for n in element.childNodes if n.nodeType == n.TEXT_NODE).strip()
        name = text.rsplit('/', 1)[-1]
        if text != 'hardware_interface/' + name:
            for node in list(element.childNodes):
                element.removeChild(node)
            element.appendChild(doc.createTextNode('hardware_interface/' + name))
            changed.append(text)
    return changed


def expand(xacro_file, mappings=None):
    """xacro_file + args -> checked URDF document (minidom), with the model's inertials set."""
    doc = run_xacro(xacro_file, mappings)
    remove_forked_gripper_roots(doc)
    check_tree(doc)
    inertials.apply(doc)
    fix_transmission_interfaces(doc)
    return doc


def expand_model(mappings=None, xacro_file=None):
    """The package's own top-level model, with the upstream packages and its args checked first."""
    check_model_packages()
    mappings = dict(mappings or {})
    if 'ur_type' in mappings:
        check_ur_type(mappings['ur_type'])
    for arg in BOOLEAN_ARGS:
        if arg in mappings:
            check_boolean(arg, mappings[arg])
    if xacro_file is None:
        xacro_file = os.path.join(package_path('ur3_ft_gripper_description'),
                                  'urdf', 'ur3_ft_gripper.xacro')
    return expand(xacro_file, mappings)


def to_xml(doc):
    return doc.toprettyxml(indent='  ')
