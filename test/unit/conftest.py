"""Shared helpers: expand the real model (real xacro, upstream packages on ROS_PACKAGE_PATH)."""
import functools
import itertools
import os
import subprocess
import sys

import pytest
import rospkg

from ur3_ft_gripper_description import description, kinematics

PACKAGE = 'ur3_ft_gripper_description'
PACKAGE_DIR = rospkg.RosPack().get_path(PACKAGE)
UR_CONFIG = os.path.join(rospkg.RosPack().get_path('ur_description'), 'config', 'ur3')
UR_CONFIG_ROOT = os.path.join(rospkg.RosPack().get_path('ur_description'), 'config')
EXPAND = [sys.executable, os.path.join(PACKAGE_DIR, 'scripts', 'expand_description')]
EXPORT = [sys.executable, os.path.join(PACKAGE_DIR, 'scripts', 'export_urdf')]

# Every model and toggle combination the package offers.
UR_TYPES = description.ur_types()
TOGGLES = [dict(ft_sensor=s, gripper=g) for s, g in itertools.product((True, False), repeat=2)]
CONFIGURATIONS = [dict(ur_type=u, **t) for u in UR_TYPES for t in TOGGLES]


def configuration_id(config):
    return '%s-%s-%s' % (config['ur_type'], 'ft' if config['ft_sensor'] else 'noft',
                         'gripper' if config['gripper'] else 'nogripper')


class ExpandedModel(kinematics.Model):
    """A model expanded by the package's own pipeline, with domain assertions."""

    def __init__(self, urdf_text):
        super(ExpandedModel, self).__init__(urdf_text)
        self.text = urdf_text

    def assert_joint_between(self, parent, child, joint_type=None):
        joint = self.parent_joint.get(child)
        assert joint is not None, 'no joint has child %s' % child
        assert joint.parent == parent, '%s hangs from %s, not %s' % (child, joint.parent, parent)
        if joint_type:
            assert joint.type == joint_type, '%s is %s, not %s' % (joint.name, joint.type, joint_type)
        return joint


@pytest.fixture
def expand_model():
    def expand(**mappings):
        return ExpandedModel(description.to_xml(description.expand_model(mappings)))
    return expand


@functools.lru_cache(maxsize=None)
def _configured(ur_type, ft_sensor, gripper, prefix=''):
    mappings = dict(ur_type=ur_type, ft_sensor=str(ft_sensor).lower(), gripper=str(gripper).lower(),
                    prefix=prefix)
    return ExpandedModel(description.to_xml(description.expand_model(mappings)))


@pytest.fixture(scope='session')
def configured_model():
    """Expands each (ur_type, ft_sensor, gripper[, prefix]) once per test session."""
    return _configured


@pytest.fixture(scope='session')
def default_model():
    return ExpandedModel(description.to_xml(description.expand_model({})))


def robotiq_variant():
    """'noetic' (jr-robotics fork) or 'kinetic' (ros-industrial), from the files present."""
    urdf = os.path.join(rospkg.RosPack().get_path('robotiq_2f_140_gripper_visualization'), 'urdf')
    return 'noetic' if os.path.exists(os.path.join(urdf, 'robotiq_arg2f_140_macro.xacro')) else 'kinetic'


def run_export(*args, env=None):
    return subprocess.run(EXPORT + list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, env=env, timeout=120)


def run_expand(*args, env=None):
    return subprocess.run(EXPAND + list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, env=env, timeout=120)
