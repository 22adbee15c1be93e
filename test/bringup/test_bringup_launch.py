"""The real-cell bring-up at launch level, against ur_robot_driver's own launch files.

ur_robot_driver's nodes cannot run here (no robot), but its package.xml,
launch/ and config/ can be on ROS_PACKAGE_PATH, and roslaunch resolves
everything up to starting the nodes: which nodes, from which packages, with
which parameters and remappings. These tests read exactly that, through
roslaunch itself (the command line and its XmlLoader), with no master.
"""
import os
import subprocess
from xml.etree import ElementTree

import numpy as np
import pytest
import rospkg
import yaml
import roslaunch.config
import roslaunch.xmlloader

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_testing.rostest_helpers import free_port

PACKAGE = 'ur3_ft_gripper_description'
PACKAGE_DIR = rospkg.RosPack().get_path(PACKAGE)
LAUNCH = os.path.join(PACKAGE_DIR, 'launch')
TEST_LAUNCH = os.path.join(PACKAGE_DIR, 'test', 'bringup')

# ur_description's kinematics sections, in the order of the arm's joints.
ARM = [('shoulder', 'shoulder_pan_joint'), ('upper_arm', 'shoulder_lift_joint'),
       ('forearm', 'elbow_joint'), ('wrist_1', 'wrist_1_joint'), ('wrist_2', 'wrist_2_joint'),
       ('wrist_3', 'wrist_3_joint')]

# What ur_robot_driver's ur_common.launch and ur_control.launch start (its nodes, not ours).
UR_DRIVER_NODES = {
    '/robot_state_publisher': ('robot_state_publisher', 'robot_state_publisher'),
    '/ur_hardware_interface': ('ur_robot_driver', 'ur_robot_driver_node'),
    '/ros_control_controller_spawner': ('controller_manager', 'spawner'),
    '/ros_control_stopped_spawner': ('controller_manager', 'spawner'),
    '/controller_stopper': ('ur_robot_driver', 'controller_stopper_node'),
    '/ur_hardware_interface/ur_robot_state_helper': ('ur_robot_driver', 'robot_state_helper'),
}
FT_DRIVER = {'/robotiq_ft_sensor': ('robotiq_ft_sensor', 'rq_sensor')}
GRIPPER_JOINT_STATES = {'/gripper_joint_states': (PACKAGE, 'gripper_joint_states')}
RTU = {'/robotiq2FGripper': ('robotiq_2f_gripper_control', 'Robotiq2FGripperRtuNode.py')}
TCP = {'/robotiq2FGripper': ('robotiq_2f_gripper_control', 'Robotiq2FGripperTcpNode.py')}
REAL_ARGS = ['robot_ip:=192.168.56.101', 'ft_serial_id:=ttyUSB0']


@pytest.fixture(scope='module', autouse=True)
def ur_robot_driver_on_path():
    try:
        rospkg.RosPack().get_path('ur_robot_driver')
    except rospkg.ResourceNotFound:
        pytest.fail('ur_robot_driver is not on ROS_PACKAGE_PATH: add $UR3_FT_GRIPPER_UPSTREAM/ur_robot_driver_data '
                    '(its package.xml, launch/ and config/; tools/quickstart does) or install ros-noetic-ur-robot-driver',
                    pytrace=False)


def calibration(tmp_path, ur_type):
    """ur_description's default kinematics for ur_type, every figure moved by its own amount."""
    default = os.path.join(rospkg.RosPack().get_path('ur_description'), 'config', ur_type,
                           'default_kinematics.yaml')
    with open(default) as f:
        data = yaml.safe_load(f)
    step = 0
    for section, _ in ARM:
        for key in ('x', 'y', 'z', 'roll', 'pitch', 'yaw'):
            step += 1
            data['kinematics'][section][key] += 0.001 * step
    data['kinematics']['hash'] = 'calib_test_%s' % ur_type
    path = tmp_path / ('%s_calibration.yaml' % ur_type)
    path.write_text(yaml.safe_dump(data))
    return str(path), data['kinematics']


def dump_params(*command):
    run = subprocess.run(['roslaunch', '--dump-params'] + list(command), stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True, timeout=180)
    # --dump-params exits 0 even when loading failed: the output is the proof.
    assert run.returncode == 0, run.stderr
    params = yaml.safe_load(run.stdout) if run.stdout.startswith('/') else None
    assert isinstance(params, dict) and '/robot_description' in params, run.stderr + run.stdout
    return params


def assert_cell_model(params, calib, prefix=''):
    """robot_description holds arm, FT 300 and 2F-140, and the arm's joint origins are calib's."""
    model = kinematics.Model(params['/robot_description'])
    for link in ('base_link', 'tool0', 'robotiq_ft_frame_id', 'robotiq_arg2f_base_link',
                 'left_inner_finger_pad', 'right_inner_finger_pad'):
        assert prefix + link in model.links, link
    model.chain(prefix + 'base_link', prefix + 'right_inner_finger_pad')  # one chain, arm to fingers
    assert model.joints[prefix + 'finger_joint'].type == 'revolute'
    for section, joint in ARM:
        c = calib[section]
        origin = model.joints[prefix + joint].origin
        np.testing.assert_allclose(list(origin.xyz) + list(origin.rpy),
                                   [c[k] for k in ('x', 'y', 'z', 'roll', 'pitch', 'yaw')], atol=1e-9,
                                   err_msg=joint)
    # ur_robot_driver compares the robot's calibration with the same file.
    assert params['/ur_hardware_interface/kinematics/hash'] == calib['hash']


@pytest.mark.parametrize('ur_type, description_file', [
    # This package's UR3 load launch file, as ur_robot_driver's robot_description_file.
    ('ur3', os.path.join(LAUNCH, 'load_ur3_ft_gripper.launch')),
    # Another model: the few lines a cell package writes around load_ur_ft_gripper.launch.
    ('ur5e', os.path.join(TEST_LAUNCH, 'load_ur5e_cell.launch')),
])
def test_drop_in_ur_robot_driver_bringup(tmp_path, ur_type, description_file):
    path, calib = calibration(tmp_path, ur_type)
    params = dump_params('ur_robot_driver', '%s_bringup.launch' % ur_type, 'robot_ip:=127.0.0.1',
                         'kinematics_config:=' + path, 'robot_description_file:=' + description_file)
    assert_cell_model(params, calib)


def load_nodes(launch_file, *args):
    """The nodes roslaunch would start, by name: (package, type, args, remaps), and the parameters."""
    config = roslaunch.config.ROSLaunchConfig()
    roslaunch.xmlloader.XmlLoader().load(os.path.join(LAUNCH, launch_file), config, verbose=False,
                                         argv=['roslaunch'] + list(args))
    nodes = {}
    for node in config.nodes:
        name = (node.namespace + node.name).replace('//', '/')
        assert name not in nodes, 'two nodes named %s' % name
        nodes[name] = node
    return nodes, {name: p.value for name, p in config.params.items()}


def kinds(nodes):
    return {name: (n.package, n.type) for name, n in nodes.items()}


def resolved_remaps(node):
    return {os.path.join(node.namespace, src): os.path.join(node.namespace, dst) for src, dst in node.remap_args}


def assert_joint_states_meet(nodes):
    """gripper_joint_states publishes where robot_state_publisher listens (the root joint_states)."""
    assert resolved_remaps(nodes['/gripper_joint_states']) == {'/gripper/joint_states': '/joint_states'}
    rsp = nodes['/robot_state_publisher']
    assert rsp.namespace == '/' and not rsp.remap_args


@pytest.mark.parametrize('launch_file, args', [
    ('ur3_ft_gripper_bringup.launch', []),
    ('ur_ft_gripper_bringup.launch', ['ur_type:=ur3']),
])
def test_real_cell_rtu(launch_file, args):
    nodes, params = load_nodes(launch_file, *(args + REAL_ARGS + ['gripper_device:=/dev/ttyUSB1']))
    assert kinds(nodes) == dict(UR_DRIVER_NODES, **FT_DRIVER, **RTU, **GRIPPER_JOINT_STATES)
    assert nodes['/robotiq2FGripper'].args == '/dev/ttyUSB1'
    assert params['/robotiq_ft_sensor/serial_id'] == 'ttyUSB0'
    assert params['/robotiq_ft_sensor/frame_id'] == 'robotiq_ft_frame_id'
    # Without calibration args, gripper_joint_states keeps its own defaults.
    assert '/gripper_joint_states/gpo_open' not in params and '/gripper_joint_states/gpo_closed' not in params
    assert params['/ur_hardware_interface/robot_ip'] == '192.168.56.101'
    assert_joint_states_meet(nodes)


def test_real_cell_tcp_with_prefix_and_calibration(tmp_path):
    path, calib = calibration(tmp_path, 'ur5e')
    nodes, params = load_nodes('ur_ft_gripper_bringup.launch', 'ur_type:=ur5e', 'prefix:=cell_',
                               'kinematics_config:=' + path, 'gripper_ip:=192.168.1.11',
                               'gripper_gpo_open:=4', 'gripper_gpo_closed:=227', 'headless_mode:=true',
                               *REAL_ARGS)
    assert kinds(nodes) == dict(UR_DRIVER_NODES, **FT_DRIVER, **TCP, **GRIPPER_JOINT_STATES)
    assert nodes['/robotiq2FGripper'].args == '192.168.1.11'
    assert params['/robotiq_ft_sensor/frame_id'] == 'cell_robotiq_ft_frame_id'
    assert params['/gripper_joint_states/prefix'] == 'cell_'
    assert (params['/gripper_joint_states/gpo_open'], params['/gripper_joint_states/gpo_closed']) == (4, 227)
    assert params['/ur_hardware_interface/tf_prefix'] == 'cell_'
    assert params['/ur_hardware_interface/headless_mode'] is True
    # ur5e's own controller configuration from ur_robot_driver.
    assert params['/ur_hardware_interface/joints'] == ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint',
                                                       'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint']
    assert_cell_model(params, calib, prefix='cell_')
    assert_joint_states_meet(nodes)


def test_real_cell_default_calibration_is_the_ur_types():
    nodes, params = load_nodes('ur_ft_gripper_bringup.launch', 'ur_type:=ur10e', 'gripper_device:=/dev/ttyUSB1',
                               *REAL_ARGS)
    default = os.path.join(rospkg.RosPack().get_path('ur_description'), 'config', 'ur10e',
                           'default_kinematics.yaml')
    with open(default) as f:
        calib = yaml.safe_load(f)['kinematics']
    assert_cell_model(params, calib)


def test_real_cell_without_the_gripper():
    nodes, params = load_nodes('ur3_ft_gripper_bringup.launch', 'gripper:=false', *REAL_ARGS)
    assert kinds(nodes) == dict(UR_DRIVER_NODES, **FT_DRIVER)
    assert 'robotiq_arg2f_base_link' not in params['/robot_description']


def test_sim_replaces_the_devices_under_the_same_names():
    nodes, params = load_nodes('ur3_ft_gripper_bringup.launch', 'sim:=true')
    assert kinds(nodes) == {
        '/robotiq_ft_sensor': (PACKAGE, 'ft300_sim'),
        '/robotiq2FGripper': (PACKAGE, 'gripper_sim'),
        '/gripper_joint_states': (PACKAGE, 'gripper_joint_states'),
        '/ur_hardware_interface': (PACKAGE, 'ur_arm_sim'),
        '/robot_state_publisher': ('robot_state_publisher', 'robot_state_publisher'),
    }
    assert_joint_states_meet(nodes)
    # ur_robot_driver's own controller configuration for ur_type, on the parameter server as
    # its ur_control.launch puts it, and read by the simulation.
    config = os.path.join(rospkg.RosPack().get_path('ur_robot_driver'), 'config', 'ur3_controllers.yaml')
    assert params['/ur_hardware_interface/controller_config_file'] == config
    assert params['/scaled_pos_joint_traj_controller/type'] == 'position_controllers/ScaledJointTrajectoryController'
    assert params['/hardware_control_loop/loop_hz'] == 125


def test_sim_gui_gives_sliders_instead_of_the_driver():
    nodes, params = load_nodes('ur3_ft_gripper_bringup.launch', 'sim:=true', 'gui:=true')
    assert '/ur_hardware_interface' not in nodes
    assert kinds(nodes)['/arm_joint_state_publisher'] == ('joint_state_publisher_gui', 'joint_state_publisher_gui')
    # The sliders know the arm only, so they never publish finger_joint.
    arm = kinematics.Model(params['/arm_joint_state_publisher/robot_description'])
    assert 'finger_joint' not in arm.joints and 'wrist_3_joint' in arm.joints
    assert 'finger_joint' in kinematics.Model(params['/robot_description']).joints


@pytest.mark.parametrize('launch_file, required', [
    ('ur_ft_gripper_bringup.launch', {'ur_type', 'robot_ip', 'ft_serial_id', 'gripper_device'}),
    ('ur3_ft_gripper_bringup.launch', {'robot_ip', 'ft_serial_id', 'gripper_device'}),
])
def test_every_arg_has_doc_and_the_required_ones_no_default(launch_file, required):
    args = ElementTree.parse(os.path.join(LAUNCH, launch_file)).getroot().findall('arg')
    for arg in args:
        assert arg.get('doc', '').strip(), ElementTree.tostring(arg)
    unset = {a.get('name') for a in args if 'default' not in a.attrib and 'value' not in a.attrib}
    assert unset == required


def roslaunch_run(*command, env=None):
    """A real roslaunch on an unused master port: it must stop while loading."""
    env = dict(env or os.environ, ROS_MASTER_URI='http://localhost:%d' % free_port())
    return subprocess.run(['roslaunch'] + list(command), stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, universal_newlines=True, env=env, timeout=180)


@pytest.mark.parametrize('missing', ['robot_ip', 'ft_serial_id', 'gripper_device'])
def test_missing_required_arg_stops_roslaunch(missing):
    given = {'robot_ip': 'robot_ip:=192.168.56.101', 'ft_serial_id': 'ft_serial_id:=ttyUSB0',
             'gripper_device': 'gripper_device:=/dev/ttyUSB1'}
    del given[missing]
    run = roslaunch_run(PACKAGE, 'ur3_ft_gripper_bringup.launch', *given.values())
    assert run.returncode == 1
    assert "requires the '%s' arg to be set" % missing in run.stderr, run.stderr
    assert 'Traceback' not in run.stderr + run.stdout
    assert 'auto-starting new master' not in run.stdout


def without_ur_robot_driver(folder):
    """The environment with every package found now, except ur_robot_driver, as links in `folder`.

    (ur_robot_driver may share a ROS_PACKAGE_PATH entry with other packages,
    e.g. /opt/ros/noetic/share, so entries cannot simply be dropped.)
    """
    rospack = rospkg.RosPack()
    for name in rospack.list():
        if name != 'ur_robot_driver':
            os.symlink(rospack.get_path(name), os.path.join(str(folder), name))
    env = dict(os.environ, ROS_PACKAGE_PATH=str(folder))
    check = subprocess.run(['rospack', 'find', 'ur_robot_driver'], env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE)
    assert check.returncode != 0, 'could not take ur_robot_driver off ROS_PACKAGE_PATH'
    return env


def test_without_ur_robot_driver_only_the_sliders_run_and_the_rest_says_it_is_missing(tmp_path):
    # The simulated arm reads ur_robot_driver's controller configuration; the sliders need nothing of it.
    env = without_ur_robot_driver(tmp_path)
    # By path: the linked package and the workspace's source space would both match a package name.
    launch_file = os.path.join(LAUNCH, 'ur3_ft_gripper_bringup.launch')
    sliders = subprocess.run(['roslaunch', '--nodes', launch_file, 'sim:=true', 'gui:=true'],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, env=env,
                             timeout=180)
    assert sliders.returncode == 0, sliders.stderr
    assert '/robotiq2FGripper' in sliders.stdout.split()
    for args in (['sim:=true'], ['gripper_device:=/dev/ttyUSB1'] + REAL_ARGS):
        run = roslaunch_run(launch_file, *args, env=env)
        assert run.returncode == 1
        assert 'ur_robot_driver' in run.stderr and 'not found' in run.stderr.lower(), run.stderr
        assert 'Traceback' not in run.stderr + run.stdout
