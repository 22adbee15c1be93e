"""Shared by the reliability tests: a real rosmaster on a free port, real roslaunch."""
import os
import subprocess
import sys
import time

import pytest

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BENCH_DIR = os.path.join(PACKAGE_DIR, 'bench')
sys.path.insert(0, BENCH_DIR)
import benchlib  # noqa: E402  (the benchmarks' own helpers: one way to start a master)


class Master(object):
    """A rosmaster this test owns; can be killed and started again on the same port."""

    def __init__(self):
        self.port = benchlib.free_port()
        self.uri = 'http://localhost:%d' % self.port
        self.env = dict(os.environ, ROS_MASTER_URI=self.uri)
        self.process = None

    def start(self):
        self.process = subprocess.Popen(['rosmaster', '--core', '-p', str(self.port)],
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        benchlib.wait_for(lambda: benchlib.master_pid(self.uri), 30, 'rosmaster on %s' % self.uri)

    def kill(self):
        self.process.kill()
        self.process.wait()


@pytest.fixture
def master():
    m = Master()
    m.start()
    yield m
    benchlib.stop(m.process)


def run(argv, env=None, timeout=300):
    return subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
                          env=env, timeout=timeout)


def wait_for(condition, timeout, what):
    return benchlib.wait_for(condition, timeout, what, step=0.2)


def topic_message(topic, env, timeout=20):
    """One message of `topic` as text, from a subscriber started now (rostopic echo); None if none."""
    try:
        got = run(['rostopic', 'echo', '-n', '1', topic], env=env, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    return got.stdout if got.returncode == 0 else None


def wait_until(predicate, timeout):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.2)
    return False
