"""The ROS master restarted under running simulated devices: they register again and serve new
subscribers, with one warning and one notice each (a real rosmaster killed and started again)."""
import subprocess
import tempfile
import time

from conftest import benchlib, topic_message, wait_until


def publishers_and_subscribers(master_uri):
    import rosgraph
    pubs, subs, _ = rosgraph.Master('/reliability', master_uri=master_uri).getSystemState()
    return dict(pubs), dict(subs)


def test_nodes_reregister_with_a_restarted_master(master):
    log = tempfile.NamedTemporaryFile('w+', suffix='.log')
    launch = subprocess.Popen(['roslaunch', 'ur3_ft_gripper_description', 'view_ur3_ft_gripper.launch',
                               'gui:=false', 'rviz:=false'], stdout=log, stderr=subprocess.STDOUT,
                              env=master.env)
    try:
        assert topic_message('/robotiq_ft_wrench', master.env, timeout=60), 'no wrench before the restart'
        master.kill()
        time.sleep(3.0)  # the nodes look once a second
        master.start()

        def registered():
            pubs, subs = publishers_and_subscribers(master.uri)
            return ('/ft300_sim' in pubs.get('/robotiq_ft_wrench', []) and
                    '/gripper_sim' in subs.get('/gripper/command', []))
        assert wait_until(registered, 20), publishers_and_subscribers(master.uri)
        # New subscribers and publishers find the nodes through the new master.
        assert 'robotiq_ft_frame_id' in (topic_message('/robotiq_ft_wrench', master.env) or '')
        subprocess.run(['rostopic', 'pub', '-1', '/gripper/command', 'std_msgs/Float64', '0.05'],
                       env=master.env, stdout=subprocess.DEVNULL, timeout=30, check=True)
        assert wait_until(lambda: 'data: 0.05\n' in (topic_message('/gripper/opening', master.env) or ''), 20)
        assert launch.poll() is None, 'roslaunch or a node exited'
    finally:
        benchlib.stop(launch)
    log.seek(0)
    output = log.read()
    for node in ('/ft300_sim', '/gripper_sim'):
        lost = [line for line in output.splitlines() if node + ': the ROS master' in line and 'unreachable' in line]
        back = [line for line in output.splitlines() if node + ': the ROS master' in line and 'restarted' in line]
        assert len(lost) == 1 and len(back) == 1, output[-3000:]
    assert 'Traceback' not in output, output[-3000:]
