"""Which way the simulated controller's imports run: the core and the network faces need no ROS, the
faces know nothing of the core or its ROS node, and the core knows nothing of its faces.

Each check imports modules in a fresh interpreter and lists what got loaded, so that a module
another test imported earlier cannot hide an import.
"""
import json
import subprocess
import sys

import pytest

PACKAGE = 'ur3_ft_gripper_description'
ROS = ('rospy', 'actionlib', 'roslib', 'rosgraph', 'tf2_ros', 'genpy')


def loaded_by(*modules):
    """The names of the modules loaded once `modules` are imported, in a fresh interpreter."""
    code = ('import importlib, json, sys\n'
            'for name in %r: importlib.import_module(name)\n'
            'print(json.dumps(sorted(sys.modules)))' % (modules,))
    out = subprocess.run([sys.executable, '-c', code], check=True, stdout=subprocess.PIPE).stdout
    return json.loads(out.decode())


def ros_in(names):
    return [n for n in names if n.split('.')[0] in ROS or n.split('.')[0].endswith('_msgs')]


@pytest.mark.parametrize('module', [
    PACKAGE + '.devices.ur_arm.core',
    PACKAGE + '.devices.network.dashboard',
    PACKAGE + '.devices.network.rtde',
    PACKAGE + '.devices.ur_arm.network_faces',
    PACKAGE + '.urscript',
])
def test_the_controller_core_and_its_network_faces_run_without_ros(module):
    assert ros_in(loaded_by(module)) == []


def test_the_network_faces_know_nothing_of_the_arm_and_the_core_nothing_of_its_faces():
    faces = loaded_by(PACKAGE + '.devices.network.dashboard', PACKAGE + '.devices.network.rtde')
    assert [n for n in faces if n.startswith(PACKAGE + '.devices.ur_arm')] == []
    core = loaded_by(PACKAGE + '.devices.ur_arm.core')
    assert [n for n in core if n.startswith(PACKAGE + '.devices.ur_arm.arm_sim') or
            n.startswith(PACKAGE + '.devices.network') or n.endswith('.network_faces')] == []


def test_the_check_sees_an_import_of_ros():
    """The planted case: the arm's ROS node itself loads rospy."""
    assert 'rospy' in ros_in(loaded_by(PACKAGE + '.devices.ur_arm.arm_sim'))
