"""The ROS master restarted under the simulated devices: each node exits with one clear line and
roslaunch (respawn="true") starts it again on the new master (a real rosmaster killed and started
again on the same port)."""
import os
import subprocess
import sys
import tempfile

from conftest import stop, topic_message, wait_for

NODES = ('/robotiq_ft_sensor', '/robotiq2FGripper', '/gripper_joint_states')


def system_state(master_uri):
    import rosgraph
    pubs, subs, services = rosgraph.Master('/reliability', master_uri=master_uri).getSystemState()
    return dict(pubs), dict(subs), dict(services)


def publishers(master_uri):
    try:
        return system_state(master_uri)[0]
    except Exception:  # the master is still coming up
        return {}


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


# The model in TF (load launch, joint_state_publisher, robot_state_publisher) without the
# simulated devices: what they need from a master. A new master starts empty, so this is
# started again on it, as a user runs their bring-up again.
MODEL = ['roslaunch', 'ur3_ft_gripper_description', 'view_ur3_ft_gripper.launch', 'sim:=false',
         'rviz:=false', 'gui:=false']


def start_model(master, log, processes):
    """The model launch (added to `processes`), once robot_state_publisher publishes TF on this master."""
    processes.append(subprocess.Popen(MODEL, stdout=log, stderr=subprocess.STDOUT, env=master.env))
    wait_for(lambda: '/robot_state_publisher' in publishers(master.uri).get('/tf', []),
             lambda: 'robot_state_publisher on /tf; log: %s' % tail(log), 60, step=0.2)


def first_messages(env):
    """A first message of each simulated node's output, from subscribers started now."""
    return {topic: topic_message(topic, env, timeout=60) or '' for topic in
            ('/robotiq_ft_wrench', '/Robotiq2FGripperRobotInput', '/gripper/joint_states')}


def assert_publishing(env, log, when):
    got = first_messages(env)
    assert 'robotiq_ft_frame_id' in got['/robotiq_ft_wrench'], (when, got, tail(log))
    assert 'gSTA' in got['/Robotiq2FGripperRobotInput'], (when, got, tail(log))
    assert 'finger_joint' in got['/gripper/joint_states'], (when, got, tail(log))


def tail(log, chars=3000):
    """The end of a roslaunch's output, for the assertion messages."""
    with open(log.name) as f:
        return f.read()[-chars:]


def test_nodes_exit_once_and_respawn_on_a_restarted_master(master):
    log = tempfile.NamedTemporaryFile('w+', suffix='.log')
    model_log = tempfile.NamedTemporaryFile('w+', suffix='.log')
    processes = []  # stopped in reverse order
    try:
        # One roslaunch after the other: two starting at once race to set /run_id.
        start_model(master, model_log, processes)
        processes.append(subprocess.Popen(['roslaunch', 'ur3_ft_gripper_description', 'sim_devices.launch'],
                                          stdout=log, stderr=subprocess.STDOUT, env=master.env))
        wait_for(lambda: registered(master.uri), lambda: 'the devices registered: %s; log: %s' % (
            system_state(master.uri), tail(log)), 60, step=0.2)
        assert_publishing(master.env, log, 'before the restart')
        stop(processes.pop(0))  # the model: a new master needs it again
        master.kill()
        master.start()
        start_model(master, model_log, processes)
        # Readiness on the new master: registration, then a first message from each node.
        wait_for(lambda: registered(master.uri), lambda: 'the devices registered: %s; log: %s' % (
            system_state(master.uri), tail(log)), 60, step=0.2)
        assert_publishing(master.env, log, 'after the restart')
        # A new publisher reaches the respawned gripper.
        subprocess.run(['rostopic', 'pub', '-1', '/Robotiq2FGripperRobotOutput',
                        'robotiq_2f_gripper_control/Robotiq2FGripper_robot_output', '{rACT: 1}'],
                       env=master.env, stdout=subprocess.DEVNULL, timeout=30, check=True)
        wait_for(lambda: 'gSTA: 3' in (topic_message('/Robotiq2FGripperRobotInput', master.env) or ''),
                 'gSTA 3 after rACT 1', 30, step=0.2)
        assert processes[0].poll() is None, 'roslaunch of sim_devices.launch exited'
    finally:
        for process in reversed(processes):
            stop(process)
    output = tail(log, chars=10 ** 7)
    for node in NODES:
        lines = [line for line in output.splitlines() if node + ': the ROS master' in line]
        assert len(lines) == 1 and 'was restarted' in lines[0] and 'exiting' in lines[0], output[-3000:]
    assert 'Traceback' not in output, output[-3000:]


def test_a_node_started_before_the_master_waits_for_it(master):
    """As roscpp nodes do: one line saying so, then the node runs on the master that comes up."""
    master.kill()
    log = tempfile.NamedTemporaryFile('w+', suffix='.log')
    node = subprocess.Popen(['rosrun', 'ur3_ft_gripper_description', 'gripper_sim'],
                            stdout=log, stderr=subprocess.STDOUT, env=master.env)
    try:
        wait_for(lambda: 'waiting for the ROS master' in tail(log), lambda: 'the line; log: %s' % tail(log), 60,
                 step=0.2)
        assert node.poll() is None, tail(log)
        master.start()
        wait_for(lambda: '/robotiq2FGripper' in system_state_or_empty(master.uri)[1].get(
            '/Robotiq2FGripperRobotOutput', []), lambda: 'gripper_sim subscribed; log: %s' % tail(log), 60, step=0.2)
        assert 'gSTA' in (topic_message('/Robotiq2FGripperRobotInput', master.env, timeout=60) or '')
    finally:
        stop(node)
    output = tail(log, chars=10 ** 7)
    assert output.count('waiting for the ROS master') == 1, output
    assert 'Traceback' not in output, output


def test_a_publishing_loop_stops_before_rospy_closes_its_topics(master):
    """rospy closes a node's topics before its is_shutdown() turns True; node_loop's loop must not
    publish in between (the node here holds that window open for a second)."""
    log = tempfile.NamedTemporaryFile('w+', suffix='.log')
    node = subprocess.Popen([sys.executable, os.path.join(os.path.dirname(__file__), 'slow_closing_publisher.py')],
                            stdout=log, stderr=subprocess.STDOUT, env=master.env)
    try:
        assert 'data:' in (topic_message('/count', master.env, timeout=60) or ''), tail(log)
        master.kill()
        master.start()
        node.wait(timeout=60)
    finally:
        stop(node)
    output = tail(log, chars=10 ** 7)
    assert node.returncode == 1, output
    assert output.count('was restarted') == 1, output
    assert 'Traceback' not in output and 'closed topic' not in output, output


def system_state_or_empty(master_uri):
    try:
        return system_state(master_uri)
    except Exception:  # the master is still coming up
        return {}, {}, {}
