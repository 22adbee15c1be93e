"""Expand xacro into a checked URDF, with one-line errors for bad input.

This is the engine behind `expand_description` (a drop-in for the xacro
command) and the launch files, in four steps:

1. xacro: the installed ROS 1 xacro reads the xacro files, the arguments and
   the parameter files by its own rules; whatever it rejects becomes one
   line naming the file and xacro's own words for the problem;
2. fix-ups of what xacro produced: the extra ``<prefix>base_link`` and its
   joint that the jr-robotics Noetic fork of the 2F-140 macro emits (they
   collide with the arm's root) are removed;
3. checks: a model that is not one tree with TF-valid names is refused, so
   that ``robot_description`` is never half-built;
4. what xacro cannot express over upstream's macros: the FT 300 and 2F-140
   links get the manufacturer's mass properties and every bare frame a
   negligible one (``inertials``), and the transmissions' hardware interfaces
   are written as ros_control names them.
"""

import os
import re
import subprocess

from ur3_ft_gripper_description.model import inertials
from ur3_ft_gripper_description.model.names import GRIPPER_BASE, DescriptionError, child_elements, package_path

# The upstream packages whose files and meshes the model uses.
MODEL_PACKAGES = ('ur_description', 'robotiq_ft_sensor', 'robotiq_2f_140_gripper_visualization')
# The file in ur_description/config/<ur_type>/ that each arg defaults to (in the macro).
UR_DEFAULT_FILES = {
    'joint_limit_params': 'joint_limits.yaml',
    'kinematics_params': 'default_kinematics.yaml',
    'physical_params': 'physical_parameters.yaml',
    'visual_params': 'visual_parameters.yaml',
}

# A TF frame name: segments of letters, digits and '_', separated by '/'.
FRAME_NAME = re.compile(r'^[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$')


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


def _causes(exc):
    """`exc` and the exceptions it was raised while handling."""
    while exc is not None:
        yield exc
        exc = exc.__cause__ or exc.__context__


def _ur_type_hint(exc):
    """'; the installed ur_description has the models ur3, ...' when xacro lacked one of their files."""
    for cause in _causes(exc):
        if isinstance(cause, FileNotFoundError) and cause.filename:
            try:
                config = os.path.realpath(os.path.join(package_path('ur_description'), 'config'))
            except DescriptionError:
                return ''
            path = os.path.realpath(cause.filename)
            if path.startswith(config + os.sep) and os.path.basename(path) in UR_DEFAULT_FILES.values():
                return '; the installed ur_description has the models %s' % ', '.join(ur_types())
    return ''


def xacro_failure(xacro_file, exc):
    """One line for what xacro rejected: the file, then xacro's words for the problem.

    xacro's message is the problem (a YAML error takes several lines), then
    one line per expression it was evaluating, innermost first: the problem
    and the innermost expression say what and where.
    """
    lines = [' '.join(line.split()) for line in str(exc).splitlines() if line.strip()]
    context = [i for i, line in enumerate(lines) if line.startswith('when ')]
    problem = ' '.join(lines[:context[0] + 1] if context else lines) or type(exc).__name__
    return '%s: %s%s' % (xacro_file, problem, _ur_type_hint(exc))


def run_xacro(xacro_file, mappings=None):
    """The installed xacro on `xacro_file` with `mappings` (its args); returns the minidom document."""
    try:
        import xacro
    except ImportError:
        raise DescriptionError(
            'xacro is not installed: sudo apt install ros-noetic-xacro, or build ros/xacro '
            '(noetic-devel) in your catkin workspace and source it') from None
    try:
        return xacro.process_file(xacro_file, mappings=dict(mappings or {}))
    except Exception as e:  # xacro raises many types; each becomes one line
        raise DescriptionError(xacro_failure(xacro_file, e)) from None


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
    joints = child_elements(robot, 'joint')
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
        same_name = [lk for lk in child_elements(robot, 'link') if lk.getAttribute('name') == parent]
        still_used = any(parent in (_link_of(j, 'parent'), _link_of(j, 'child'))
                         for j in child_elements(robot, 'joint'))
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
    for link in child_elements(doc.documentElement, 'link'):
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


def correct_for_consumers(doc):
    """What plain xacro cannot express over upstream's macros: mass properties and interface names."""
    inertials.apply(doc)
    fix_transmission_interfaces(doc)


def expand(xacro_file, mappings=None):
    """xacro_file + args -> checked URDF document (minidom), with the model's inertials set."""
    doc = run_xacro(xacro_file, mappings)
    remove_forked_gripper_roots(doc)
    check_tree(doc)
    correct_for_consumers(doc)
    return doc


def expand_model(mappings=None, xacro_file=None):
    """The package's own top-level model (urdf/ur3_ft_gripper.xacro) for `mappings`."""
    if xacro_file is None:
        xacro_file = os.path.join(package_path('ur3_ft_gripper_description'),
                                  'urdf', 'ur3_ft_gripper.xacro')
    return expand(xacro_file, mappings)


def to_xml(doc):
    return doc.toprettyxml(indent='  ')
