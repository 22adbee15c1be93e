"""The ROS master restarted under the simulated devices: each node exits with one clear line and
roslaunch (respawn="true") starts it again on the new master (a real rosmaster killed and started
again on the same port)."""
import subprocess
import tempfile

import yaml

from conftest import benchlib, topic_message, wait_until

NODES = ('/robotiq_ft_sensor', '/robotiq2FGripper', '/gripper_joint_states')


def system_state(master_uri):
    import rosgraph
    pubs, subs, services = rosgraph.Master('/reliability', master_uri=master_uri).getSystemState()
    return dict(pubs), dict(subs), dict(services)


def registered(master_uri):
    """Every simulated device's topics and service are known to the master at `master_uri`."""
    try:
        pubs, subs, services = system_state(master_uri)
    except Exception:  # the master is still coming up
        return False
    return ('/robotiq_ft_sensor' in pubs.get('/robotiq_ft_wrench', []) and
            '/robotiq_ft_sensor' in services.get('/robotiq_ft_sensor_acc', []) and
            '/robotiq2FGripper' in subs.get('/Robotiq2FGripperRobotOutput', []) and
            '/gripper_joint_states' in pubs.get('/gripper/joint_states', []))


def set_model(master, description):
    """robot_description and a static sensor pose: what the respawned nodes need from the new master."""
    import rosgraph
    rosgraph.Master('/reliability', master_uri=master.uri).setParam('/robot_description', description)
    return subprocess.Popen(['rosrun', 'tf2_ros', 'static_transform_publisher', '0', '0', '0', '0', '0',
                             '3.14159', 'base_link', 'robotiq_ft_frame_id', '__name:=sensor_pose'],
                            env=master.env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def test_nodes_exit_once_and_respawn_on_a_restarted_master(master):
    dump = subprocess.run(['roslaunch', '--dump-params', 'ur3_ft_gripper_description',
                           'load_ur3_ft_gripper.launch'], stdout=subprocess.PIPE,
                          universal_newlines=True, env=master.env, check=True).stdout
    description = yaml.safe_load(dump)['/robot_description']
    log = tempfile.NamedTemporaryFile('w+', suffix='.log')
    pose = set_model(master, description)
    launch = subprocess.Popen(['roslaunch', 'ur3_ft_gripper_description', 'sim_devices.launch'],
                              stdout=log, stderr=subprocess.STDOUT, env=master.env)
    try:
        assert wait_until(lambda: registered(master.uri), 60), system_state(master.uri)
        assert topic_message('/robotiq_ft_wrench', master.env, timeout=60), 'no wrench before the restart'
        master.kill()
        pose.kill()
        pose.wait()
        master.start()
        pose = set_model(master, description)
        # Readiness on the new master: registration, then a first message from each node.
        assert wait_until(lambda: registered(master.uri), 60), system_state(master.uri)
        assert 'robotiq_ft_frame_id' in (topic_message('/robotiq_ft_wrench', master.env, timeout=60) or '')
        assert 'gSTA' in (topic_message('/Robotiq2FGripperRobotInput', master.env, timeout=60) or '')
        assert 'finger_joint' in (topic_message('/gripper/joint_states', master.env, timeout=60) or '')
        # A new publisher reaches the respawned gripper.
        subprocess.run(['rostopic', 'pub', '-1', '/Robotiq2FGripperRobotOutput',
                        'robotiq_2f_gripper_control/Robotiq2FGripper_robot_output', '{rACT: 1}'],
                       env=master.env, stdout=subprocess.DEVNULL, timeout=30, check=True)
        assert wait_until(lambda: 'gSTA: 3' in (topic_message('/Robotiq2FGripperRobotInput', master.env) or ''), 30)
        assert launch.poll() is None, 'roslaunch exited'
    finally:
        benchlib.stop(launch)
        pose.kill()
        pose.wait()
    log.seek(0)
    output = log.read()
    for node in NODES:
        lines = [line for line in output.splitlines() if node + ': the ROS master' in line]
        assert len(lines) == 1 and 'was restarted' in lines[0] and 'exiting' in lines[0], output[-3000:]
    assert 'Traceback' not in output, output[-3000:]
