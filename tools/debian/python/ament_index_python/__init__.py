"""Debian only (12 and 13): the one call PyPI's xacro 2 makes for ``$(find pkg)``, answered from ROS_PACKAGE_PATH."""
from .packages import PackageNotFoundError, get_package_share_directory

__all__ = ['PackageNotFoundError', 'get_package_share_directory']
