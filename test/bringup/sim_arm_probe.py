#!/usr/bin/env python3
"""A client of the simulated arm's driver interface, for test_sim_arm_models.py: prints what it saw as JSON.

Run with ROS_MASTER_URI set to the master of one bring-up; a process of its
own because rospy talks to one master per process. It asks, as a user's code
would: get_robot_software_version, zero_ftsensor, whether
dashboard/is_in_remote_control exists, the controllers, and the period of the
scaled trajectory controller's state topic (the arm's control loop publishes
it every cycle, stamped with the cycle's time).
"""
import json
import statistics
import sys

import rospy
import rosservice
from control_msgs.msg import JointTrajectoryControllerState
from controller_manager_msgs.srv import ListControllers
from std_srvs.srv import Trigger
from ur_msgs.srv import GetRobotSoftwareVersion
from ur3_ft_gripper_testing.ur_driver import HW

TIMEOUT = 120.0
STAMPS = 200


def main():
    rospy.init_node('sim_arm_probe', anonymous=True)
    rospy.wait_for_service(HW + 'get_robot_software_version', TIMEOUT)
    version = rospy.ServiceProxy(HW + 'get_robot_software_version', GetRobotSoftwareVersion)()
    rospy.wait_for_service(HW + 'zero_ftsensor', TIMEOUT)
    zero = rospy.ServiceProxy(HW + 'zero_ftsensor', Trigger)()
    rospy.wait_for_service('/controller_manager/list_controllers', TIMEOUT)
    controllers = rospy.ServiceProxy('/controller_manager/list_controllers', ListControllers)().controller
    stamps = []
    sub = rospy.Subscriber('/scaled_pos_joint_traj_controller/state', JointTrajectoryControllerState,
                           lambda msg: stamps.append(msg.header.stamp.to_sec()), queue_size=STAMPS * 2)
    end = rospy.get_time() + TIMEOUT
    while len(stamps) < STAMPS and rospy.get_time() < end and not rospy.is_shutdown():
        rospy.sleep(0.05)
    sub.unregister()
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    print(json.dumps({
        'version': [version.major, version.minor, version.bugfix, version.build],
        'zero_ftsensor': [zero.success, zero.message],
        'is_in_remote_control': HW + 'dashboard/is_in_remote_control' in rosservice.get_service_list(),
        'running': sorted(c.name for c in controllers if c.state == 'running'),
        'median_period': statistics.median(gaps) if gaps else None,
    }))
    return 0


if __name__ == '__main__':
    sys.exit(main())
