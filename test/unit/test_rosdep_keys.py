"""Every dependency key in package.xml resolves on each Ubuntu release users install on.

Noetic runs on Ubuntu 20.04 (focal), ROS-O (ROS_DISTRO=one) on 22.04 (jammy)
and 24.04 (noble). A key resolves on a release when it is a rosdep key with an
entry for that release (or a generic ubuntu one) in rosdistro's base.yaml or
python.yaml; on focal a package that Noetic releases (noetic/distribution.yaml),
on jammy and noble one whose Noetic repository ROS-O also builds (its build list,
test/data/ros_one_repositories.yaml: ROS-O's own rosdep file is not among the
upstream data); or a package of a repository pinned in repos/robotiq-*.repos,
which users build in their catkin workspace (doc/install.md). package.xml's `condition`
attributes are evaluated with that release's ROS_DISTRO, as rosdep does.
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
ROS_O = {'ROS_DISTRO': 'one', 'ROS_VERSION': '1', 'ROS_PYTHON_VERSION': '3'}
RELEASES = {'focal': NOETIC, 'jammy': ROS_O, 'noble': ROS_O}  # Ubuntu release: its ROS environment
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


def package_keys(environment):
    """The keys rosdep reads from package.xml with ROS `environment` (its conditions evaluated)."""
    package = parse_package(os.path.join(PACKAGE_DIR, 'package.xml'))
    package.evaluate_conditions(environment)
    deps = (package.buildtool_depends + package.build_depends + package.build_export_depends +
            package.buildtool_export_depends + package.exec_depends + package.test_depends +
            package.doc_depends)
    return sorted({d.name for d in deps if d.evaluated_condition})


def on_release(entry, release):
    """Whether a rosdep rule has something to install on Ubuntu `release`."""
    ubuntu = entry.get('ubuntu') if isinstance(entry, dict) else None
    if isinstance(ubuntu, list):
        return bool(ubuntu)  # one rule for every Ubuntu release
    if not isinstance(ubuntu, dict):
        return False
    if release in ubuntu:
        return bool(ubuntu[release])  # release: null means "not available"
    if '*' in ubuntu:
        return bool(ubuntu['*'])
    return bool(set(ubuntu) & {'apt', 'pip', 'source'})  # an installer rule for every release


def noetic_packages():
    """{package: the last part of its source repository's URL} for every package Noetic releases."""
    packages = {}
    for name, repo in load('noetic-distribution.yaml')['repositories'].items():
        release = repo.get('release') or {}
        if release.get('version'):
            url = (repo.get('source') or release).get('url', '')
            for package in release.get('packages', [name]):
                packages[package] = url.rstrip('/').rsplit('/', 1)[-1].replace('.git', '')
    return packages


@functools.lru_cache(maxsize=None)
def ros_one():
    with open(os.path.join(PACKAGE_DIR, 'test', 'data', 'ros_one_repositories.yaml')) as f:
        return yaml.safe_load(f)


def released(key, release):
    """Whether the ROS distribution of Ubuntu `release` releases the package `key`."""
    repository = noetic_packages().get(key)
    if repository is None:
        return False
    if RELEASES[release] is NOETIC:
        return True
    built = {name.lower() for name in ros_one()['repositories']}
    if release == 'noble' and repository in ros_one()['not_on_noble']:
        return False
    return repository.lower() in built


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


def resolves(key, release):
    rules = dict(load('base.yaml'), **load('python.yaml'))
    if key in rules:
        return on_release(rules[key], release)
    return released(key, release) or from_user_repository(key)


@pytest.mark.parametrize('release, key', [(release, key) for release, environment in RELEASES.items()
                                          for key in package_keys(environment)])
def test_key_resolves_on_each_release(release, key):
    assert resolves(key, release), (
        "'%s' is no rosdep key with a %s rule, no Noetic package and no package of the repositories in "
        "repos/%s: give it a `condition` in package.xml or a documented alternative (doc/install.md)"
        % (key, release, ' or repos/'.join(USER_REPOS_FILES)))


@pytest.mark.parametrize('key, release, expected', [
    ('python3-rospkg', 'noble', True),    # python.yaml: ubuntu: [python3-rospkg]
    ('rospkg', 'focal', False),           # a Python module, not a rosdep key
    ('xacro', 'jammy', True),             # released in Noetic, rebuilt by ROS-O
    ('ur_dashboard_msgs', 'noble', True),  # Universal_Robots_ROS_Driver, built by ROS-O
    ('canopen_master', 'focal', True),    # ros_canopen: released in Noetic ...
    ('canopen_master', 'jammy', False),   # ... and not in ROS-O's build list
    ('gazebo_ros', 'jammy', True),        # gazebo_ros_pkgs: built by ROS-O for jammy ...
    ('gazebo_ros', 'noble', False),       # ... a known failure on noble
    ('robotiq_ft_sensor', 'noble', True),  # not released: built from repos/robotiq-*.repos
    ('python3-pymodbus', 'jammy', True),  # ubuntu: {'*': ...}
    ('python3-transforms3d', 'focal', True),  # focal: pip, the others: '*'
    ('python3-absl', 'focal', True),      # a focal rule among other releases' rules
    ('python3-beartype', 'focal', False),  # focal: null
    ('sdformat', 'jammy', True),          # rules for focal and jammy ...
    ('sdformat', 'noble', False),         # ... and none for noble
    ('python-crypto', 'focal', False),    # rules for older Ubuntu releases only
    ('no_such_package', 'noble', False),
])
def test_the_check_itself(key, release, expected):
    assert resolves(key, release) is expected


def test_sdformat_is_asked_for_only_where_noetic_runs():
    # base.yaml's sdformat has no noble rule; package.xml's condition keeps
    # rosdep on ROS-O from asking for it.
    assert 'sdformat' in package_keys(NOETIC)
    assert 'sdformat' not in package_keys(ROS_O)
