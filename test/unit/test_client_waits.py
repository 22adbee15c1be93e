"""The clients wait for the driver's nodes to come up on the wall clock, and for what the cell does on ROS time.

A process coming up (its servers, topics, first messages) takes wall time however fast a simulated
cell's clock runs: at real_time_factor 0 a 60 s wait on ROS time can end after a few wall seconds,
before a starved process has even connected. The waits run here with rospy as installed and no
node: a wait on ROS time has no clock then and fails at once.
"""
import time

import pytest
import rospy

from ur3_ft_gripper_description import clients

# s of wall time to wait for a condition that never comes true.
SHORT = 0.3


def test_waiting_for_a_node_returns_the_first_true_value():
    answers = iter([None, 0, 'up'])
    assert clients.wait_until_up(rospy, lambda: next(answers), 'the answer', SHORT) == 'up'


def test_waiting_for_a_node_ends_after_its_wall_clock_timeout_naming_what_did_not_come():
    start = time.monotonic()
    with pytest.raises(clients.CellError, match=r'^no action server x \(is the arm up\?\) within 0\.3 s$'):
        clients.wait_until_up(rospy, lambda: False, 'action server x (is the arm up?)', SHORT)
    assert time.monotonic() - start >= SHORT


def test_waiting_for_the_cell_is_on_ros_time_which_needs_a_node():
    with pytest.raises(rospy.exceptions.ROSInitException):
        clients.wait_until(rospy, lambda: False, 'a cell event', SHORT)
