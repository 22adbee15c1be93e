"""What the model's modules and the simulated devices share: upstream frame names and small helpers.

The bottom of the package's imports: it imports nothing of the package, so
anything may take a frame name from here without loading the xacro engine.
"""

# ur_description's flange frame (before the prefix): where an e-Series measures the tool's wrench.
FLANGE = 'tool0'
# Names both upstream 2F-140 macros give (before the prefix).
GRIPPER_BASE = 'robotiq_arg2f_base_link'
FINGER_JOINT = 'finger_joint'
PADS = ('left_inner_finger_pad', 'right_inner_finger_pad')


class DescriptionError(Exception):
    """Bad input or environment; the message is one line naming problem and fix."""


# One rospkg.RosPack per package path: each new one crawls the whole path again (tens of ms), and the
# package's own files are looked up every time a node, a controller or a test's cell starts.
_ROSPACKS = {}


def shared_rospack():
    """The process's rospkg.RosPack for the ROS_PACKAGE_PATH (and ROS_ROOT) now set."""
    import rospkg
    paths = tuple(rospkg.get_ros_paths())
    rospack = _ROSPACKS.get(paths)
    if rospack is None:
        rospack = _ROSPACKS[paths] = rospkg.RosPack(ros_paths=list(paths))
    return rospack


def package_path(name, rospack=None):
    """Path of ROS package `name`, or DescriptionError naming it."""
    import rospkg
    try:
        return (rospack or shared_rospack()).get_path(name)
    except rospkg.ResourceNotFound:
        raise DescriptionError(
            "ROS package '%s' not found on ROS_PACKAGE_PATH: install it or add its folder there" % name) from None


def child_elements(element, tag):
    """The direct children of `element` named `tag`, in document order (not the deeper ones).

    xml.dom.minidom elements, as xacro hands documents over.
    """
    return [n for n in element.childNodes if n.nodeType == n.ELEMENT_NODE and n.tagName == tag]
