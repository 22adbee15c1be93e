"""The simulated bring-up on every UR model both ur_robot_driver and ur_description know.

Each model's `ur_ft_gripper_bringup.launch sim:=true ur_type:=X` runs on its
own rosmaster (roslaunch -p on a free port), one after the other, and a
client of the driver's interface (sim_arm_probe.py, a process per master)
reads what the controller generation decides: the software version,
whether zero_ftsensor is served, whether dashboard/is_in_remote_control
exists, and the control loop's period.
"""
import json
import math
import os
import subprocess
import sys

import pytest

from ur3_ft_gripper_description.devices.ur_arm import software
from ur3_ft_gripper_testing.rostest_helpers import free_port, stop_group, wait_for

PACKAGE = 'ur3_ft_gripper_description'
PROBE = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'sim_arm_probe.py')
# Universal Robots' CB3 arms; every other model runs the e-Series software (PolyScope 5).
# Their control loops: CB3 125 Hz, e-Series 500 Hz.
CB3_MODELS = ('ur3', 'ur5', 'ur10')


def roslaunch(port, log, *args):
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % port)
    return subprocess.Popen(['roslaunch', '-p', str(port), PACKAGE] + list(args), stdout=log,
                            stderr=subprocess.STDOUT, env=env, start_new_session=True), env


@pytest.mark.parametrize('ur_type', sorted(software.read_table()))
def test_the_simulated_bring_up_runs_each_model_as_its_generation(ur_type, tmp_path):
    port = free_port()
    with open(str(tmp_path / 'roslaunch.log'), 'w') as log:
        launch, env = roslaunch(port, log, 'ur_ft_gripper_bringup.launch', 'sim:=true', 'ur_type:=%s' % ur_type)
        try:
            probe = subprocess.run([sys.executable, PROBE], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                   universal_newlines=True, timeout=300)
            running = launch.poll() is None
        finally:
            stop_group(launch)
    output = (tmp_path / 'roslaunch.log').read_text()
    assert probe.returncode == 0, probe.stderr[-2000:] + output[-3000:]
    assert running, 'the bring-up ended: %s' % output[-3000:]
    seen = json.loads(probe.stdout.strip().splitlines()[-1])
    cb3 = ur_type in CB3_MODELS
    assert (seen['version'][0] < 5) == cb3, seen
    success, message = seen['zero_ftsensor']
    assert success == (not cb3), message
    assert seen['is_in_remote_control'] == (not cb3), seen
    assert 'scaled_pos_joint_traj_controller' in seen['running'], seen
    # Within a factor 2 of the generation's control period: tells 125 Hz from 500 Hz on a busy machine.
    period = 1.0 / (125 if cb3 else 500)
    assert seen['median_period'] and abs(math.log(seen['median_period'] / period)) < math.log(2.0), seen


def test_a_model_the_simulated_arm_does_not_know_is_one_line(tmp_path):
    # ur_robot_driver has a controllers file for ur15; the table does not list it (the installed
    # ur_description has no ur15), so the node stops before it looks for a model.
    port = free_port()
    with open(str(tmp_path / 'roslaunch.log'), 'w') as log:
        launch, _ = roslaunch(port, log, 'sim_arm.launch', 'ur_type:=ur15')
        try:
            wait_for(lambda: launch.poll() is not None, 'roslaunch to end when its required node stops', 120)
        finally:
            stop_group(launch)
    output = (tmp_path / 'roslaunch.log').read_text()
    lines = [line for line in output.splitlines() if "'ur15' is not a UR model the simulated arm knows" in line]
    assert len(lines) == 1, output
    assert 'ur3, ur3e, ur5, ur5e, ur10, ur10e, ur16e, ur20, ur30' in lines[0]
    assert 'Traceback' not in output
