"""``get_package_share_directory`` for ROS 1 packages: rospkg's lookup, as ROS 1 xacro's ``$(find)``."""
import os

import rospkg

_crawls = {}  # one crawl of the package path per ROS_PACKAGE_PATH value, as a RosPack caches it


class PackageNotFoundError(KeyError):
    """The package is not on ROS_PACKAGE_PATH (ament_index_python's name for it)."""


def get_package_share_directory(package_name):
    package_path = os.environ.get('ROS_PACKAGE_PATH', '')
    rospack = _crawls.setdefault(package_path, rospkg.RosPack())
    try:
        return rospack.get_path(package_name)
    except rospkg.ResourceNotFound:
        raise PackageNotFoundError(
            "package '{}' not found on ROS_PACKAGE_PATH".format(package_name)) from None
