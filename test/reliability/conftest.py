"""Shared by the reliability tests: a real rosmaster on a free port, real roslaunch."""
import os
import subprocess

import pytest

from ur3_ft_gripper_testing.rostest_helpers import free_port, master_pid, stop, wait_for


class Master(object):
    """A rosmaster this test owns; can be killed and started again on the same port."""

    def __init__(self):
        self.port = free_port()
        self.uri = 'http://localhost:%d' % self.port
        self.env = dict(os.environ, ROS_MASTER_URI=self.uri)
        self.process = None

    def start(self):
        self.process = subprocess.Popen(['rosmaster', '--core', '-p', str(self.port)],
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wait_for(lambda: master_pid(self.uri), 'rosmaster on %s' % self.uri, 30, step=0.2)

    def kill(self):
        self.process.kill()
        self.process.wait()


@pytest.fixture
def master():
    m = Master()
    m.start()
    yield m
    stop(m.process)


def run(argv, env=None, timeout=300):
    return subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
                          env=env, timeout=timeout)


def topic_message(topic, env, timeout=20):
    """One message of `topic` as text, from a subscriber started now (rostopic echo); None if none."""
    try:
        got = run(['rostopic', 'echo', '-n', '1', topic], env=env, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    return got.stdout if got.returncode == 0 else None
