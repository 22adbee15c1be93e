"""Shared by the rostest nodes of this folder: recording a topic, TF as matrices, the pad gap."""
import threading
import time

import numpy as np
import rospy
from transforms3d.quaternions import quat2mat

from ur3_ft_gripper_description.devices import gripper_model
from ur3_ft_gripper_description.model import description

TIMEOUT = 30.0


def transform_matrix(msg):
    """4x4 matrix of a geometry_msgs/Transform."""
    t = np.eye(4)
    q = msg.rotation
    t[:3, :3] = quat2mat((q.w, q.x, q.y, q.z))
    t[:3, 3] = (msg.translation.x, msg.translation.y, msg.translation.z)
    return t


def lookup(buffer, target, source, timeout=TIMEOUT):
    """The latest pose of `source` in `target` from tf2, as a 4x4 matrix."""
    msg = buffer.lookup_transform(target, source, rospy.Time(0), rospy.Duration(timeout))
    return transform_matrix(msg.transform)


def pad_gap(buffer, fingers, prefix=''):
    """Gap between the finger pads' inner faces in TF (`fingers`: a gripper_model.GripperKinematics)."""
    left, right = (lookup(buffer, prefix + description.GRIPPER_BASE, prefix + pad) for pad in description.PADS)
    return gripper_model.pad_gap(left, right, fingers.pad_thickness)


def wait_for_subscribers(publisher, timeout=TIMEOUT):
    """Until `publisher` has a subscriber; AssertionError after `timeout` s."""
    end = time.monotonic() + timeout
    while publisher.get_num_connections() == 0:
        if time.monotonic() > end:
            raise AssertionError('nobody subscribed to %s within %g s' % (publisher.resolved_name, timeout))
        time.sleep(0.05)


class Recorder(object):
    """Messages of one topic with their receipt time."""

    def __init__(self, topic, msg_type):
        self.items = []
        self.lock = threading.Lock()
        rospy.Subscriber(topic, msg_type, self._add, queue_size=1000)

    def _add(self, msg):
        with self.lock:
            self.items.append((time.monotonic(), msg))

    def since(self, t):
        with self.lock:
            return [m for (r, m) in self.items if r >= t]

    def next_after(self, t, timeout=TIMEOUT):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            got = self.since(t)
            if got:
                return got[0]
            time.sleep(0.01)
        raise AssertionError('nothing received within %g s' % timeout)
