"""The model as its consumers get it: exported or expanded by this package's own commands.

These tests run in a Python of their own (tools/quickstart's consumers venv:
pinocchio with coal, MuJoCo, PyBullet, python-fcl, numpy 2), not in the ROS
workspace's, so they do not import the ROS modules: the model is made by
`rosrun ur3_ft_gripper_description export_urdf` / `export_mjcf` and
`rosrun xacro xacro`, exactly as a user makes it, with the workspace sourced.
"""
import functools
import os
import subprocess
import tempfile

import numpy as np
import pytest
import yaml

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FOLDER = tempfile.mkdtemp(prefix='ur3_ft_gripper_consumers_')
ARM_JOINTS = ('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint',
              'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint')
FT300_LINKS = ('ft300_mounting_plate', 'ft300_sensor')
GRIPPER_LINKS = ('robotiq_arg2f_base_link',) + tuple(
    '%s_%s' % (side, part) for side in ('left', 'right')
    for part in ('outer_knuckle', 'outer_finger', 'inner_finger', 'inner_finger_pad', 'inner_knuckle'))

# What each part must weigh (kg): the Robotiq FT 300 manual's figures, and ur_description's arm.
with open(os.path.join(PACKAGE_DIR, 'config', 'robotiq_mass.yaml')) as _f:
    ROBOTIQ = yaml.safe_load(_f)
FT300_MASS = ROBOTIQ['ft300']['mass']
GRIPPER_MASS = ROBOTIQ['ft300_with_2f140']['mass'] - FT300_MASS

# (options, id): the model with both parts, and each part alone.
CONFIGURATIONS = [([], 'ft_sensor-gripper'), (['--no-ft-sensor'], 'gripper'), (['--no-gripper'], 'ft_sensor')]


def run(command):
    done = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                          timeout=300)
    assert done.returncode == 0, '%s failed: %s' % (' '.join(command), done.stderr)
    return done


@functools.lru_cache(maxsize=None)
def exported_urdf(*options):
    """Path of `export_urdf --absolute-meshes OPTIONS`'s file."""
    path = os.path.join(FOLDER, 'model%s.urdf' % ''.join(options))
    run(['rosrun', 'ur3_ft_gripper_description', 'export_urdf', '--absolute-meshes', '-o', path] + list(options))
    return path


@functools.lru_cache(maxsize=None)
def srdf(*mappings):
    """Path of the SRDF that plain xacro makes of config/ur3_ft_gripper.srdf.xacro with MAPPINGS."""
    path = os.path.join(FOLDER, 'model%s.srdf' % ''.join(mappings).replace(':=', '-'))
    run(['rosrun', 'xacro', 'xacro', os.path.join(PACKAGE_DIR, 'config', 'ur3_ft_gripper.srdf.xacro'),
         '-o', path] + list(mappings))
    return path


def srdf_mappings(options):
    """The SRDF's xacro args for export_urdf OPTIONS."""
    return ('ft_sensor:=%s' % str('--no-ft-sensor' not in options).lower(),
            'gripper:=%s' % str('--no-gripper' not in options).lower())


def ur_arm_mass():
    """Sum of the arm links' masses in ur_description's UR3 parameters."""
    path = os.path.join(run(['rospack', 'find', 'ur_description']).stdout.strip(),
                        'config', 'ur3', 'physical_parameters.yaml')
    with open(path) as f:
        inertia = yaml.safe_load(f)['inertia_parameters']
    return sum(inertia['%s_mass' % link] for link in
               ('base', 'shoulder', 'upper_arm', 'forearm', 'wrist_1', 'wrist_2', 'wrist_3'))


# Frames without geometry weigh 10 mg each in the model (see model/inertials.py):
# totals agree within this.
FRAMES_TOLERANCE = 2e-4


def expected_total_mass(options):
    return (ur_arm_mass() + (0 if '--no-ft-sensor' in options else FT300_MASS)
            + (0 if '--no-gripper' in options else GRIPPER_MASS)
            + (coupling_mass() if '--no-ft-sensor' in options and '--no-gripper' not in options else 0))


def coupling_mass():
    with open(os.path.join(PACKAGE_DIR, 'config', 'link_inertials.yaml')) as f:
        return yaml.safe_load(f)['links']['robotiq_arg2f_coupling']['mass']


@pytest.fixture(params=CONFIGURATIONS, ids=[c[1] for c in CONFIGURATIONS])
def options(request):
    return request.param[0]

