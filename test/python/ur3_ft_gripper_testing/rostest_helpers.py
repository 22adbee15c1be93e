"""The tests' one helper module: free ports, waits that fail loudly, recording a topic, TF as matrices.

The rostest nodes, the pytest folders and bench/ import it as
`from ur3_ft_gripper_testing import rostest_helpers`. Every wait here ends in
an AssertionError naming what did not happen: none falls through.
"""
import os
import random
import signal
import socket
import subprocess
import threading
import time
import xmlrpc.client

import numpy as np
import rospy
from transforms3d.quaternions import quat2mat

from ur3_ft_gripper_description.devices import gripper_model, sim_params, wrench_model
from ur3_ft_gripper_description.model.names import GRIPPER_BASE, PADS

TIMEOUT = 30.0
# What the simulated FT 300 reads before SET_ZERO beside its load (fx fy fz N, tx ty tz N m): the unit's
# offset of config/sim_devices.yaml, for tests that read a sensor they have not zeroed.
FT300_UNIT_OFFSET = np.array(wrench_model.load_sensor_spec(sim_params.default_devices_file()).unit_offset)


def transform_matrix(msg):
    """4x4 matrix of a geometry_msgs/Transform."""
    t = np.eye(4)
    q = msg.rotation
    t[:3, :3] = quat2mat((q.w, q.x, q.y, q.z))
    t[:3, 3] = (msg.translation.x, msg.translation.y, msg.translation.z)
    return t


def lookup(buffer, target, source, timeout=TIMEOUT, stamp=None):
    """The pose of `source` in `target` from tf2 at `stamp` (rospy.Time; None: the latest it has), as a 4x4
    matrix; waits up to `timeout` for TF to reach `stamp`."""
    msg = buffer.lookup_transform(target, source, stamp or rospy.Time(0), rospy.Duration(timeout))
    return transform_matrix(msg.transform)


def pad_gap(buffer, fingers, prefix=''):
    """Gap between the finger pads' inner faces in TF (`fingers`: a gripper_model.GripperKinematics)."""
    left, right = (lookup(buffer, prefix + GRIPPER_BASE, prefix + pad) for pad in PADS)
    return gripper_model.pad_gap(left, right, fingers.pad_thickness)


# Below the kernel's ephemeral ports (32768 on) and the UR controller's (29999 to 30013), which the
# simulated cells serve.
FREE_PORTS = range(15000, 29000)


def free_port():
    """A TCP port nobody listens on now, e.g. for a rosmaster of one's own.

    Not one the kernel picks for bind(0): between this check and the master's
    own bind, every ROS node that starts (this run's, or a second run's on the
    same machine) takes such ports for its servers, and one took a master's
    port once. A port from FREE_PORTS is taken only by a process that names it.
    """
    rng = random.SystemRandom()
    for _ in range(1000):
        port = rng.choice(FREE_PORTS)
        with socket.socket() as s:
            try:
                s.bind(('', port))
            except OSError:
                continue
            return port
    raise AssertionError('no free TCP port in %d..%d' % (FREE_PORTS[0], FREE_PORTS[-1]))


def master_pid(uri):
    """pid of the ROS master at `uri`, None while none answers there."""
    try:
        return xmlrpc.client.ServerProxy(uri).getPid('/test')[2]
    except OSError:
        return None


def node_pid(name):
    """pid of the ROS node `name`, from its own slave API (the master says where it listens)."""
    import rosgraph
    caller = rospy.get_name()
    uri = rosgraph.Master(caller).lookupNode(rospy.resolve_name(name))
    return xmlrpc.client.ServerProxy(uri).getPid(caller)[2]


def stop(process, timeout=30):
    """SIGINT (what roslaunch and rospy expect), then SIGKILL if it does not go.

    30 s: roslaunch itself gives a node 15 s after SIGINT, then SIGTERM, then
    SIGKILL; killing roslaunch sooner left a node that hung in shutdown orphaned.
    """
    if process is None or process.poll() is not None:
        return
    process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


def stop_group(process, timeout=30):
    """stop() a process started with start_new_session=True, then kill whatever of its group is left
    (e.g. the rosmaster of a roslaunch that had to be killed)."""
    if process is None:
        return
    stop(process, timeout)
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def wait_for(condition, what, timeout=TIMEOUT, step=0.05):
    """The first true value of `condition()`; after `timeout` s an AssertionError naming `what`
    (a text, or a function giving it then, e.g. with the end of a log) and the last value."""
    end = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > end:
            raise AssertionError('timed out after %g s waiting for %s (last: %r)' % (
                timeout, what() if callable(what) else what, value))
        time.sleep(step)


def cell_link(timeout=60.0):
    """A link.CellClient of the physics cell beside this node (ur_hardware_interface in its namespace), once
    it serves: MuJoCo's own figures (`truth()`) to judge the interfaces by."""
    from ur3_ft_gripper_description.devices.physics import link

    def connect():
        try:
            return link.CellClient(link.node_cell_address(rospy)[0])
        except link.LinkError:
            return None
    return wait_for(connect, 'the physics cell', timeout)


def wait_for_result(client, timeout=TIMEOUT):
    """The terminal status of the goal that actionlib SimpleActionClient `client` sent last, once its
    result has arrived (client.get_result() then has it).

    Not the client's own wait_for_result: the client tracks a goal only once
    send_goal() returns, after publishing it, so the transitions of a goal that
    a server ends at once (set_mode on a robot already running) can arrive
    before and be dropped ("Got a transition callback on a goal handle that
    we're not tracking"), and wait_for_result then waits in vain. The goal
    handle has the status and the result all the same (they come on two
    topics: the terminal status can be there before the result).
    """
    from actionlib_msgs.msg import GoalStatus
    terminal = (GoalStatus.PREEMPTED, GoalStatus.SUCCEEDED, GoalStatus.ABORTED, GoalStatus.REJECTED,
                GoalStatus.RECALLED)

    def ended():
        state = client.get_state()
        return state in terminal and client.get_result() is not None and state
    return wait_for(ended, 'the result of the goal sent to %s' % client.action_client.ns, timeout)


def wait_for_subscribers(publisher, timeout=TIMEOUT):
    """Until `publisher` has a subscriber (a message sent before that is lost)."""
    wait_for(publisher.get_num_connections, 'a subscriber of %s' % publisher.resolved_name, timeout)


def logs(rosout, node, level, text, since=0.0):
    """Texts of `node`'s /rosout messages at `level` containing `text`, received since `since`."""
    return [m.msg for (r, m) in rosout.items_since(since) if m.name == node and m.level == level
            and text in m.msg]


def wait_for_log(rosout, node, level, text, since=0.0, timeout=TIMEOUT):
    """Until `node` has logged `text` (a Recorder of /rosout). A node's messages arrive in order,
    so everything it logged before this message has arrived too: count after such a fence."""
    return wait_for(lambda: logs(rosout, node, level, text, since), '%s to log %r' % (node, text), timeout)


class Recorder(object):
    """Messages of one topic with their receipt time."""

    def __init__(self, topic, msg_type, keep=None):
        """`keep(msg)`: record only the messages it is true for (default: all)."""
        self.items = []
        self.lock = threading.Lock()
        self.topic = topic
        self.keep = keep
        rospy.Subscriber(topic, msg_type, self._add, queue_size=1000)

    def _add(self, msg):
        if self.keep is not None and not self.keep(msg):
            return
        with self.lock:
            self.items.append((time.monotonic(), msg))

    def items_since(self, t):
        """(receipt time, message) pairs received at or after `t`."""
        with self.lock:
            return [(r, m) for (r, m) in self.items if r >= t]

    def since(self, t):
        return [m for (_, m) in self.items_since(t)]

    def latest(self):
        """The last message received, or None."""
        with self.lock:
            return self.items[-1][1] if self.items else None

    def next_after(self, t, timeout=TIMEOUT):
        return wait_for(lambda: self.since(t), 'a message on %s' % self.topic, timeout, step=0.01)[0]

    def stamped_after(self, stamp, timeout=TIMEOUT):
        """The first message whose header stamp is at or after `stamp` (rospy.Time): a node on a busy machine
        may publish what it measured earlier after messages received later."""
        def found():
            with self.lock:
                return next((m for (_, m) in self.items if m.header.stamp >= stamp), None)
        return wait_for(found, 'a message on %s stamped at or after %.3f s' % (self.topic, stamp.to_sec()),
                        timeout, step=0.01)
