"""What test/unit shares: the package's paths and scripts, every configuration, and the expanded model with domain assertions.

The real model, expanded by the package's own pipeline (real xacro, the upstream packages on
ROS_PACKAGE_PATH). Fixtures stay in test/unit/conftest.py.
"""
import functools
import itertools
import os
import subprocess
import sys

import numpy as np
import rospkg

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.model import description

PACKAGE = 'ur3_ft_gripper_description'
PACKAGE_DIR = rospkg.RosPack().get_path(PACKAGE)
UR_CONFIG = os.path.join(rospkg.RosPack().get_path('ur_description'), 'config', 'ur3')
UR_CONFIG_ROOT = os.path.join(rospkg.RosPack().get_path('ur_description'), 'config')
EXPAND = [sys.executable, os.path.join(PACKAGE_DIR, 'scripts', 'expand_description')]
EXPORT = [sys.executable, os.path.join(PACKAGE_DIR, 'scripts', 'export_urdf')]
EXPORT_MJCF = [sys.executable, os.path.join(PACKAGE_DIR, 'scripts', 'export_mjcf')]

# Every model and toggle combination the package offers.
UR_TYPES = description.ur_types()
TOGGLES = [dict(ft_sensor=s, gripper=g) for s, g in itertools.product((True, False), repeat=2)]
CONFIGURATIONS = [dict(ur_type=u, **t) for u in UR_TYPES for t in TOGGLES]


def configuration_id(config):
    return '%s-%s-%s' % (config['ur_type'], 'ft' if config['ft_sensor'] else 'noft',
                         'gripper' if config['gripper'] else 'nogripper')


class ExpandedModel(kinematics.Model):
    """A model expanded by the package's own pipeline (urdf_parser_py underneath), with domain assertions."""

    def __init__(self, urdf_text):
        super(ExpandedModel, self).__init__(urdf_text)
        self.text = urdf_text

    # -- what the model says ---------------------------------------------------

    def origin_xyz(self, joint):
        return list(self.joints[joint].origin.xyz)

    def limits(self, joint):
        limit = self.joints[joint].limit
        return (limit.lower, limit.upper)

    def mimic_of(self, joint):
        """(source joint, multiplier, offset) of a mimic joint, None for an actuated one."""
        mimic = self.joints[joint].mimic
        if mimic is None:
            return None
        return (mimic.joint, 1.0 if mimic.multiplier is None else mimic.multiplier, mimic.offset or 0.0)

    def meshes(self, link=None):
        """Mesh geometries (urdf_parser_py Mesh: filename, scale) of one link or of all."""
        links = [self.robot.link_map[link]] if link else self.robot.links
        return [part.geometry for lk in links for part in list(lk.visuals) + list(lk.collisions)
                if hasattr(part.geometry, 'filename')]

    def mass(self, link):
        return self.robot.link_map[link].inertial.mass

    def path_to_root(self, link):
        """`link`, its parent, ... the root."""
        return [link] + [joint.parent for joint in reversed(self.chain(self.root(), link))]

    def to_root(self, link, positions=None):
        return self.transform(self.root(), link, positions)

    # -- domain assertions -----------------------------------------------------

    def assert_contains_link(self, link):
        assert link in self.links, 'the model has no link %s' % link

    def assert_lacks_link(self, link):
        assert link not in self.links, 'the model has a link %s' % link

    def assert_joint_between(self, parent, child, joint_type=None):
        self.assert_contains_link(child)
        joint = self.parent_joint.get(child)
        assert joint is not None, 'no joint has child %s' % child
        assert joint.parent == parent, '%s hangs from %s, not %s' % (child, joint.parent, parent)
        if joint_type:
            assert joint.type == joint_type, '%s is %s, not %s' % (joint.name, joint.type, joint_type)
        return joint

    def assert_physical_inertial(self, link):
        """An inertial with mass > 0 whose tensor is positive definite and meets the triangle inequality."""
        inertial = self.robot.link_map[link].inertial
        assert inertial is not None, '%s has no <inertial>' % link
        assert inertial.mass > 0, '%s has mass %r' % (link, inertial.mass)
        i = inertial.inertia
        tensor = np.array([[i.ixx, i.ixy, i.ixz], [i.ixy, i.iyy, i.iyz], [i.ixz, i.iyz, i.izz]])
        principal = np.linalg.eigvalsh(tensor)
        assert principal.min() > 0, '%s: inertia not positive definite: %s' % (link, principal)
        a, b, c = sorted(principal)
        assert a + b >= c * (1 - 1e-9), '%s: principal moments %s break the triangle inequality' % (
            link, principal)

    def com_in(self, frame, links, positions=None):
        """(total mass, centre of mass in `frame`) of `links`."""
        total, moment = 0.0, np.zeros(3)
        for link in links:
            inertial = self.robot.link_map[link].inertial
            t = self.transform(frame, link, positions).dot(kinematics.pose_matrix(inertial.origin))
            total += inertial.mass
            moment += inertial.mass * t[:3, 3]
        return total, moment / total

    def assert_mesh_resolves(self, mesh):
        """A package:// URI of an upstream model package, naming a file that exists."""
        uri = mesh.filename
        assert uri.startswith('package://'), uri
        package, _, relative = uri[len('package://'):].partition('/')
        assert package in description.MODEL_PACKAGES, uri
        assert os.path.isfile(os.path.join(rospkg.RosPack().get_path(package), relative)), uri


def expand(**mappings):
    """The model expanded with these xacro arguments."""
    return ExpandedModel(description.to_xml(description.expand_model(mappings)))


@functools.lru_cache(maxsize=None)
def configured(ur_type, ft_sensor, gripper, prefix=''):
    """The model of one configuration, expanded once per process."""
    return expand(ur_type=ur_type, ft_sensor=str(ft_sensor).lower(), gripper=str(gripper).lower(),
                  prefix=prefix)


def robotiq_variant():
    """'noetic' (jr-robotics fork) or 'kinetic' (ros-industrial), from the files present."""
    urdf = os.path.join(rospkg.RosPack().get_path('robotiq_2f_140_gripper_visualization'), 'urdf')
    return 'noetic' if os.path.exists(os.path.join(urdf, 'robotiq_arg2f_140_macro.xacro')) else 'kinetic'


def run_export(*args, env=None, command=EXPORT, cwd=None):
    return subprocess.run(command + list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, env=env, cwd=cwd, timeout=120)


def run_expand(*args, env=None):
    return subprocess.run(EXPAND + list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, env=env, timeout=120)


def assert_one_line_error(run, *words):
    assert run.returncode == 1, run.stderr
    assert run.stdout == '', 'a URDF was printed despite the error'
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1, run.stderr
    assert lines[0].startswith('expand_description: error: ')
    assert 'Traceback' not in run.stderr
    for word in words:
        assert word in lines[0], (word, lines[0])
