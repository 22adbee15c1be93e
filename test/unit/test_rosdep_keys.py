"""Every dependency key in package.xml resolves for ROS Noetic on Ubuntu 20.04 (focal).

A key resolves when it is a rosdep key with a focal (or a generic ubuntu)
entry in rosdistro's base.yaml or python.yaml, a package that Noetic releases
(noetic/distribution.yaml), or a package of a repository pinned in
repos/robotiq-*.repos, which users build in their catkin workspace (doc/install.md).
The rosdistro files come from $UR3_FT_GRIPPER_ROSDISTRO (tools/quickstart sets it);
nothing is downloaded.
"""
import functools
import os

import pytest
import rospkg
import yaml
from catkin_pkg.package import parse_package

from ur3_ft_gripper_testing.model import PACKAGE_DIR

NOETIC = {'ROS_DISTRO': 'noetic', 'ROS_VERSION': '1', 'ROS_PYTHON_VERSION': '3'}
USER_REPOS_FILES = ('robotiq-noetic.repos', 'robotiq-kinetic.repos')


def rosdistro_file(name):
    folder = os.environ.get('UR3_FT_GRIPPER_ROSDISTRO')
    assert folder, ('UR3_FT_GRIPPER_ROSDISTRO is not set: point it at a folder with rosdistro\'s '
                    'base.yaml, python.yaml and noetic-distribution.yaml')
    path = os.path.join(folder, name)
    assert os.path.isfile(path), '%s not found (UR3_FT_GRIPPER_ROSDISTRO)' % path
    return path


@functools.lru_cache(maxsize=None)
def load(name):
    with open(rosdistro_file(name)) as f:
        return yaml.safe_load(f)


def package_keys():
    package = parse_package(os.path.join(PACKAGE_DIR, 'package.xml'))
    package.evaluate_conditions(NOETIC)
    deps = (package.buildtool_depends + package.build_depends + package.build_export_depends +
            package.buildtool_export_depends + package.exec_depends + package.test_depends +
            package.doc_depends)
    return sorted({d.name for d in deps if d.evaluated_condition})


def on_focal(entry):
    """Whether a rosdep rule has something to install on Ubuntu focal."""
    ubuntu = entry.get('ubuntu') if isinstance(entry, dict) else None
    if isinstance(ubuntu, list):
        return bool(ubuntu)  # one rule for every Ubuntu release
    if not isinstance(ubuntu, dict):
        return False
    if 'focal' in ubuntu:
        return bool(ubuntu['focal'])  # focal: null means "not available"
    if '*' in ubuntu:
        return bool(ubuntu['*'])
    return bool(set(ubuntu) & {'apt', 'pip', 'source'})  # an installer rule for every release


def noetic_packages():
    packages = set()
    for name, repo in load('noetic-distribution.yaml')['repositories'].items():
        release = repo.get('release') or {}
        if release.get('version'):
            packages.update(release.get('packages', [name]))
    return packages


def user_repositories():
    """Folder names of the repositories that README has users clone (vcs import names them so)."""
    names = set()
    for name in USER_REPOS_FILES:
        with open(os.path.join(PACKAGE_DIR, 'repos', name)) as f:
            names.update(yaml.safe_load(f)['repositories'])
    return names


def from_user_repository(key):
    try:
        path = os.path.realpath(rospkg.RosPack().get_path(key))
    except rospkg.ResourceNotFound:
        return False
    return bool(set(path.split(os.sep)) & user_repositories())


def resolves(key):
    rules = dict(load('base.yaml'), **load('python.yaml'))
    if key in rules:
        return on_focal(rules[key])
    return key in noetic_packages() or from_user_repository(key)


@pytest.mark.parametrize('key', package_keys())
def test_key_resolves_for_noetic_on_focal(key):
    assert resolves(key), ("'%s' is no rosdep key with a focal rule, no Noetic package and no package of "
                           "the repositories in repos/%s" % (key, ' or repos/'.join(USER_REPOS_FILES)))


@pytest.mark.parametrize('key, expected', [
    ('python3-rospkg', True),    # python.yaml: ubuntu: [python3-rospkg]
    ('rospkg', False),           # a Python module, not a rosdep key
    ('xacro', True),             # released in Noetic
    ('robotiq_ft_sensor', True),  # not released: built from repos/robotiq-*.repos
    ('python3-pymodbus', True),  # ubuntu: {'*': ...}
    ('python3-absl', True),      # a focal rule among other releases' rules
    ('python3-beartype', False),  # focal: null
    ('python-crypto', False),    # rules for older Ubuntu releases only
    ('no_such_package', False),
])
def test_the_check_itself(key, expected):
    assert resolves(key) is expected
