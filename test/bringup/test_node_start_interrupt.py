"""Ctrl-C while a node starts: it ends without a traceback.

roslaunch sends SIGINT to every node when a required one fails, and some are
then still importing or waiting for the master. Their tracebacks would bury
the one line that says what was wrong. Each node is started as users start it
(rosrun), with no master at its ROS_MASTER_URI, and interrupted twice: at
once (it is importing) and once it says it waits for the master. The
ROS-free controller is interrupted at once and once it listens; from then on
Ctrl-C closes its interfaces and it exits 0.
"""
import os
import signal
import socket
import subprocess
import time

import pytest

from ur3_ft_gripper_testing.rostest_helpers import free_port

PACKAGE = 'ur3_ft_gripper_description'
ROS_NODES = ['ft300_sim', 'gripper_joint_states', 'gripper_sim', 'ur_arm_sim']
COME_UP = 60.0  # wall s for a node to import and reach its wait for the master


def start(script, *args):
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % free_port())
    return subprocess.Popen(['rosrun', PACKAGE, script] + list(args), stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, universal_newlines=True, env=env)


def sigint_default(pid):
    """Whether the process leaves SIGINT to its default action: neither caught (Python's own handler, from its
    start until the node's first line) nor ignored (inherited from a shell's background job)."""
    with open('/proc/%d/status' % pid) as status:
        masks = dict(line.split(':\t', 1) for line in status if line.startswith(('SigCgt', 'SigIgn')))
    return not any(int(masks[name], 16) & (1 << (signal.SIGINT - 1)) for name in ('SigCgt', 'SigIgn'))


def importing(process):
    """Once the node's script has handed Ctrl-C to its default (its first lines) and imports its modules.

    Not earlier: while Python itself starts (its site module, before any line of the script) a Ctrl-C
    ends any Python program with a traceback, or is ignored where the shell that started it ignores it."""
    deadline = time.monotonic() + COME_UP
    while True:
        try:
            with open('/proc/%d/cmdline' % process.pid, 'rb') as cmdline:
                if b'python' in cmdline.read() and sigint_default(process.pid):
                    return
        except FileNotFoundError:
            pass
        assert process.poll() is None and time.monotonic() < deadline, 'the node\'s script did not start'
        time.sleep(0.001)


def interrupted(process):
    """The process's output after SIGINT, once it ended."""
    process.send_signal(signal.SIGINT)
    output, _ = process.communicate(timeout=30)
    return output


def read_until(process, words):
    """The process's output up to the first line holding `words`."""
    lines = []
    deadline = time.monotonic() + COME_UP
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        assert line, 'the node ended before saying %r: %s' % (words, ''.join(lines))
        lines.append(line)
        if words in line:
            return ''.join(lines)
    raise AssertionError('no %r within %g s: %s' % (words, COME_UP, ''.join(lines)))


@pytest.mark.parametrize('script', ROS_NODES)
def test_a_node_interrupted_while_it_imports_ends_without_a_traceback(script):
    process = start(script)
    importing(process)
    output = interrupted(process)
    assert 'Traceback' not in output and process.returncode == -signal.SIGINT, output


@pytest.mark.parametrize('script', ROS_NODES)
def test_a_node_interrupted_while_it_waits_for_the_master_ends_without_a_traceback(script):
    process = start(script)
    said = read_until(process, 'waiting for the ROS master')
    output = said + interrupted(process)
    assert 'Traceback' not in output and process.returncode == -signal.SIGINT, output


def test_the_controller_interrupted_while_it_starts_ends_without_a_traceback():
    process = start('ur_controller_sim', '--ur-type', 'ur3', '--robot-ip', '127.0.0.1')
    importing(process)
    output = interrupted(process)
    assert 'Traceback' not in output and process.returncode == -signal.SIGINT, output


def test_the_controller_interrupted_once_it_listens_closes_its_interfaces_and_exits_0():
    address = '127.0.%d.%d' % (os.getpid() % 250 + 1, 7)
    process = start('ur_controller_sim', '--ur-type', 'ur3', '--robot-ip', address)
    said = read_until(process, 'dashboard server on')  # the first of the faces it announces
    output = said + interrupted(process)
    assert 'Traceback' not in output and process.returncode == 0, output
    with pytest.raises(ConnectionRefusedError):
        socket.create_connection((address, 30004), timeout=5.0)
