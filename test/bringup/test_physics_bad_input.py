"""physics:=true with bad input: one line each, and nothing half-started.

- A world file with a missing mass, an unknown shape, an object inside the table:
  `ur3_ft_gripper_bringup.launch sim:=true physics:=true world:=...` on its own rosmaster; the arm's
  node says what is wrong in one line naming the file and the field, and, being required, ends the
  launch.
- A real-time factor that is negative or not a number, a /clock rate below the FT 300's, and a second node publishing /clock beside the
  simulated cell's clock (a bag played with --clock): one line from the arm's node, and the launch ends.
- MuJoCo not installed: the arm's node run with physics by a Python that has everything the
  workspace's has but MuJoCo (a venv made here from the workspace's, its packages linked in but
  mujoco's), against a real master with the model and the controllers loaded: one line with the
  install command, exit status 1.
"""
import glob
import os
import subprocess
import sys
import sysconfig

import pytest
import rospkg

from ur3_ft_gripper_description.model import description, export
from ur3_ft_gripper_testing.rostest_helpers import free_port, master_pid, stop_group, wait_for

PACKAGE = 'ur3_ft_gripper_description'
PACKAGE_DIR = rospkg.RosPack().get_path(PACKAGE)

TABLE = """
table:
  size: [1.0, 1.2, 0.04]
  pose: [0.2, 0.0, -0.02]
  friction: 0.5
"""
BAD_WORLDS = {
    'missing_mass': (TABLE + """
objects:
  - name: box
    shape: box
    size: [0.05, 0.05, 0.1]
    pose: [0.3, -0.15, 0.05]
    friction: 0.5
""", ['objects[0] (box): no mass', 'give its mass in kg']),
    'unknown_shape': (TABLE + """
objects:
  - name: ball
    shape: sphere
    size: [0.05, 0.05, 0.05]
    pose: [0.3, -0.15, 0.05]
    mass: 0.1
    friction: 0.5
""", ["objects[0] (ball): unknown shape 'sphere'", 'use box, cylinder, mesh']),
    'inside_the_table': (TABLE + """
objects:
  - name: box
    shape: box
    size: [0.05, 0.05, 0.1]
    pose: [0.3, -0.15, 0.0]
    mass: 0.3
    friction: 0.5
""", ['objects[0] (box) is inside the table', 'mm deep', 'raise its pose z']),
}


def one_line(output, words):
    """The one line of roslaunch's `output` holding all `words`; the failure leads with what went wrong
    (CI logs keep the start of a message), then the output's end."""
    lines = [line for line in output.splitlines() if all(word in line for word in words)]
    assert len(lines) == 1, '%d lines hold %r (want 1): %r; the output ends: %s' % (
        len(lines), words, lines, output[-4000:])
    assert 'Traceback' not in output, 'a traceback: %s' % output[output.index('Traceback'):][:4000]
    return lines[0]


def launch_until_it_ends(tmp_path, arguments, port=None):
    """roslaunch of the bring-up with sim:=true physics:=true and `arguments` on its own master; its output
    once it ended (its required arm node stopped)."""
    port = port or free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % port)
    log_path = str(tmp_path / 'roslaunch.log')
    with open(log_path, 'w') as log:
        launch = subprocess.Popen(['roslaunch', '-p', str(port), PACKAGE, 'ur3_ft_gripper_bringup.launch', 'sim:=true',
                                   'physics:=true'] + arguments, stdout=log, stderr=subprocess.STDOUT,
                                  env=env, start_new_session=True)
        try:
            wait_for(lambda: launch.poll() is not None, 'roslaunch to end when its required node stops', 120)
        finally:
            stop_group(launch)
    return open(log_path).read()


@pytest.mark.parametrize('case', sorted(BAD_WORLDS))
def test_a_bad_world_file_is_one_line_and_ends_the_launch(case, tmp_path):
    text, words = BAD_WORLDS[case]
    world = tmp_path / 'world.yaml'
    world.write_text(text)
    line = one_line(launch_until_it_ends(tmp_path, ['world:=%s' % world]), [str(world)] + words)
    assert 'ur_hardware_interface' in line


@pytest.mark.parametrize('argument, words', [
    ('real_time_factor:=-1', ['~real_time_factor', 'must be >= 0']),
    ('real_time_factor:=fast', ['~real_time_factor', 'is not a number']),
    # /clock in 20 ms steps would make the FT 300's node serve two of its 10 ms samples at once.
    ('pub_clock_frequency:=50', ['~pub_clock_frequency=50', 'use 0 (every control cycle) or at least 100 Hz']),
])
def test_a_bad_clock_setting_is_one_line_and_ends_the_launch(argument, words, tmp_path):
    line = one_line(launch_until_it_ends(tmp_path, [argument]), words)
    assert 'ur_hardware_interface' in line and '[FATAL]' in line


def test_a_second_clock_is_one_line_naming_it_and_ends_the_launch(tmp_path):
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % port)
    master = subprocess.Popen(['rosmaster', '--core', '-p', str(port)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, env=env, start_new_session=True)
    rival = None
    try:
        wait_for(lambda: master_pid(env['ROS_MASTER_URI']), 'rosmaster on port %d' % port, 30)
        # What `rosbag play --clock` does: another node publishing /clock.
        rival = subprocess.Popen(['rostopic', 'pub', '-r', '10', '/clock', 'rosgraph_msgs/Clock',
                                  '{clock: {secs: 1, nsecs: 0}}', '__name:=bag_player'],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, start_new_session=True)
        import rosgraph
        wait_for(lambda: any(topic == '/clock' for topic, nodes in
                             rosgraph.Master('/test', master_uri=env['ROS_MASTER_URI']).getSystemState()[0]),
                 'the other node to publish /clock', 30)
        output = launch_until_it_ends(tmp_path, [], port=port)
    finally:
        if rival is not None:
            stop_group(rival)
        stop_group(master)
    line = one_line(output, ['/bag_player', 'publishes /clock too'])
    assert 'use_sim_time:=false' in line and 'ur_hardware_interface' in line, line


@pytest.fixture
def python_without_mujoco(tmp_path):
    """A Python with the workspace's packages but MuJoCo's: a venv whose site-packages links the others in."""
    venv = tmp_path / 'venv'
    subprocess.run([sys.executable, '-m', 'venv', '--system-site-packages', '--without-pip', str(venv)], check=True)
    python = str(venv / 'bin' / 'python3')
    target = subprocess.run([python, '-c', 'import sysconfig; print(sysconfig.get_paths()["purelib"])'],
                            stdout=subprocess.PIPE, universal_newlines=True, check=True).stdout.strip()
    for entry in glob.glob(os.path.join(sysconfig.get_paths()['purelib'], '*')):
        name = os.path.basename(entry)
        if not name.lower().startswith('mujoco') and not os.path.exists(os.path.join(target, name)):
            os.symlink(entry, os.path.join(target, name))
    check = subprocess.run([python, '-c', 'import numpy, rospy, trimesh, urdf_parser_py; import mujoco'],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    assert check.returncode != 0 and "No module named 'mujoco'" in check.stderr, check.stderr
    return python


def test_physics_without_mujoco_is_one_line_with_the_install_command(python_without_mujoco, tmp_path):
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % port)
    master = subprocess.Popen(['rosmaster', '--core', '-p', str(port)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, env=env, start_new_session=True)
    try:
        wait_for(lambda: master_pid(env['ROS_MASTER_URI']), 'rosmaster on port %d' % port, 30)
        import xmlrpc.client
        api = xmlrpc.client.ServerProxy(env['ROS_MASTER_URI'])
        urdf = description.to_xml(description.expand_model(export.model_mappings()))
        api.setParam('/test', '/robot_description', urdf)
        config = os.path.join(rospkg.RosPack().get_path('ur_robot_driver'), 'config', 'ur3_controllers.yaml')
        subprocess.run(['rosparam', 'load', config], env=env, check=True, timeout=60)
        node = subprocess.run(
            [python_without_mujoco, os.path.join(PACKAGE_DIR, 'scripts', 'ur_arm_sim'), '__name:=ur_hardware_interface',
             '_physics:=true', '_ur_type:=ur3', '_controller_config_file:=%s' % config,
             '_controllers:=joint_state_controller scaled_pos_joint_traj_controller'],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=120)
    finally:
        stop_group(master)
    assert node.returncode == 1, node.stdout[-3000:]
    line = one_line(node.stdout, ['physics needs MuJoCo'])
    assert 'pip install mujoco' in line and 'python3-mujoco-pip' in line, line
    assert '[FATAL]' in line
