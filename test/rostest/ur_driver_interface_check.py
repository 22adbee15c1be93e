#!/usr/bin/env python3
"""rostest node: every element of ur_robot_driver's documented ROS interface exists, with its documented type.

The table below is written from ur_robot_driver 2.4.1's documents (each
block names its section), resolved as the bring-up's defaults resolve them:
the hardware interface node is `ur_hardware_interface` (ur_control.launch),
robot_state_helper runs in its namespace, the controllers and the
controller_manager at the root. It runs against the bring-up as a user
starts it (ur_driver_interface.test: sim:=true ur_type:=ur5e, nothing else),
so that a renamed, retyped or lost element fails here.
"""
import unittest

import rosgraph
import rospy
import rosservice
import rostest
import tf2_ros
from controller_manager_msgs.srv import ListControllers, SwitchController, SwitchControllerRequest
from std_msgs.msg import Bool, String
from std_srvs.srv import Trigger

from ur3_ft_gripper_testing import cpu_load
from ur3_ft_gripper_testing.rostest_helpers import TIMEOUT, wait_for, wait_for_subscribers
from ur3_ft_gripper_testing.ur_driver import HW

TRIGGER = 'std_srvs/Trigger'

# ROS_INTERFACE.md, "Nodes > ur_robot_driver_node > Advertised Services" (the node is
# ur_control.launch's ur_hardware_interface; the dashboard client lives in its dashboard/).
SERVICES = {HW + 'dashboard/' + name: kind for name, kind in [
    ('add_to_log', 'ur_dashboard_msgs/AddToLog'), ('brake_release', TRIGGER),
    ('clear_operational_mode', TRIGGER), ('close_popup', TRIGGER), ('close_safety_popup', TRIGGER),
    ('connect', TRIGGER), ('get_loaded_program', 'ur_dashboard_msgs/GetLoadedProgram'),
    ('get_robot_mode', 'ur_dashboard_msgs/GetRobotMode'), ('get_safety_mode', 'ur_dashboard_msgs/GetSafetyMode'),
    ('load_installation', 'ur_dashboard_msgs/Load'), ('load_program', 'ur_dashboard_msgs/Load'),
    ('pause', TRIGGER), ('play', TRIGGER), ('popup', 'ur_dashboard_msgs/Popup'), ('power_off', TRIGGER),
    ('power_on', TRIGGER), ('program_running', 'ur_dashboard_msgs/IsProgramRunning'),
    ('program_saved', 'ur_dashboard_msgs/IsProgramSaved'),
    # "only available on e-Series models": the bring-up here is a ur5e.
    ('is_in_remote_control', 'ur_dashboard_msgs/IsInRemoteControl'),
    ('program_state', 'ur_dashboard_msgs/GetProgramState'),
    # The document's type; the driver's source serves std_srvs/Trigger here.
    ('quit', 'ur_dashboard_msgs/GetLoadedProgram'),
    ('raw_request', 'ur_dashboard_msgs/RawRequest'), ('restart_safety', TRIGGER), ('shutdown', TRIGGER),
    ('stop', TRIGGER), ('unlock_protective_stop', TRIGGER)]}
SERVICES.update({HW + name: kind for name, kind in [
    ('hand_back_control', TRIGGER), ('resend_robot_program', TRIGGER), ('set_io', 'ur_msgs/SetIO'),
    ('set_speed_slider', 'ur_msgs/SetSpeedSliderFraction'), ('set_payload', 'ur_msgs/SetPayload'),
    ('zero_ftsensor', TRIGGER),
    # Not in ROS_INTERFACE.md; ur_robot_driver's integration test calls it.
    ('get_robot_software_version', 'ur_msgs/GetRobotSoftwareVersion')]})
# controllers.md, "How do controllers get loaded and started?": the controller_manager's services.
SERVICES.update({'/controller_manager/' + name: 'controller_manager_msgs/' + kind for name, kind in [
    ('list_controllers', 'ListControllers'), ('switch_controller', 'SwitchController'),
    ('load_controller', 'LoadController'), ('unload_controller', 'UnloadController'),
    ('list_controller_types', 'ListControllerTypes'),
    ('reload_controller_libraries', 'ReloadControllerLibraries')]})

# Published by the driver: (topic, type).
PUBLISHED = [
    # ROS_INTERFACE.md, "ur_robot_driver_node > Published topics".
    (HW + 'robot_program_running', 'std_msgs/Bool'),
    # ROS_INTERFACE.md, "robot_state_helper > Subscribed topics": published by the driver
    # in the namespace robot_state_helper runs in.
    (HW + 'robot_mode', 'ur_dashboard_msgs/RobotMode'),
    (HW + 'safety_mode', 'ur_dashboard_msgs/SafetyMode'),
    # Not in ROS_INTERFACE.md; ur_robot_driver's integration test reads it after set_io.
    (HW + 'io_states', 'ur_msgs/IOStates'),
    # controllers.md, "Read-Only controllers" (speed_scaling_factor: the bring-up's speed_scaling_id).
    ('/joint_states', 'sensor_msgs/JointState'),
    ('/wrench', 'geometry_msgs/WrenchStamped'),
    ('/speed_scaling_factor', 'std_msgs/Float64'),
]
# Subscribed by the driver: (topic, type).
SUBSCRIBED = [
    # ROS_INTERFACE.md, "ur_robot_driver_node > Subscribed topics".
    (HW + 'script_command', 'std_msgs/String'),
    # controllers.md, "Commanding controllers": the topic interfaces.
    ('/joint_group_vel_controller/command', 'std_msgs/Float64MultiArray'),
    ('/twist_controller/command', 'geometry_msgs/Twist'),
]
# Action servers: (namespace, action type).
ACTIONS = [
    # ROS_INTERFACE.md, "robot_state_helper": "offers an action to set the robot to a specific mode",
    # started in the hardware interface's namespace by ur_control.launch.
    (HW + 'set_mode', 'ur_dashboard_msgs/SetMode'),
]
# controllers.md, "Commanding controllers": control_msgs/FollowJointTrajectory ...
ACTIONS += [('/%s/follow_joint_trajectory' % name, 'control_msgs/FollowJointTrajectory') for name in (
    'scaled_pos_joint_traj_controller', 'pos_joint_traj_controller', 'vel_joint_traj_controller',
    'scaled_vel_joint_traj_controller', 'forward_joint_traj_controller')]
# ... and cartesian_control_msgs/FollowCartesianTrajectory.
ACTIONS += [('/%s/follow_cartesian_trajectory' % name, 'cartesian_control_msgs/FollowCartesianTrajectory')
            for name in ('forward_cartesian_traj_controller', 'pose_based_cartesian_traj_controller',
                         'joint_based_cartesian_traj_controller')]

# controllers.md, each controller's **Type:**, and <ur_type>_bringup.launch's `controllers`
# (started) and `stopped_controllers` (loaded, stopped) defaults.
CONTROLLER_TYPES = {
    'joint_state_controller': 'joint_state_controller/JointStateController',
    'force_torque_sensor_controller': 'force_torque_sensor_controller/ForceTorqueSensorController',
    'speed_scaling_state_controller': 'scaled_controllers/SpeedScalingStateController',
    'scaled_pos_joint_traj_controller': 'position_controllers/ScaledJointTrajectoryController',
    'joint_group_vel_controller': 'velocity_controllers/JointGroupVelocityController',
    'twist_controller': 'ros_controllers_cartesian/TwistController',
    'pos_joint_traj_controller': 'position_controllers/JointTrajectoryController',
    'vel_joint_traj_controller': 'velocity_controllers/JointTrajectoryController',
    'scaled_vel_joint_traj_controller': 'velocity_controllers/ScaledJointTrajectoryController',
    'forward_joint_traj_controller': 'pass_through_controllers/JointTrajectoryController',
    # controllers.md says pass_through_controllers/JointTrajectoryController for this one too;
    # the config it points to gives the Cartesian class.
    'forward_cartesian_traj_controller': 'pass_through_controllers/CartesianTrajectoryController',
    'pose_based_cartesian_traj_controller': 'pose_controllers/CartesianTrajectoryController',
    'joint_based_cartesian_traj_controller': 'position_controllers/CartesianTrajectoryController',
}
STARTED = ['joint_state_controller', 'scaled_pos_joint_traj_controller', 'speed_scaling_state_controller',
           'force_torque_sensor_controller']
STOPPED = ['pos_joint_traj_controller', 'joint_group_vel_controller']

# controllers.md, twist_controller and the config's Cartesian controllers: the robot's own TCP frame.
TF_FRAMES = [('base', 'tool0_controller')]


def action_topics(namespace, action):
    """The topics an action server publishes and subscribes, with their types (actionlib's protocol)."""
    return ([(namespace + '/status', 'actionlib_msgs/GoalStatusArray'),
             (namespace + '/result', action + 'ActionResult'),
             (namespace + '/feedback', action + 'ActionFeedback')],
            [(namespace + '/goal', action + 'ActionGoal'), (namespace + '/cancel', 'actionlib_msgs/GoalID')])


class DocumentedInterfaceTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.wait_for_service('/controller_manager/list_controllers', TIMEOUT)
        rospy.wait_for_service(HW + 'set_io', TIMEOUT)
        cls.master = rosgraph.Master(rospy.get_name())

    def graph(self):
        publishers, subscribers, _ = self.master.getSystemState()
        types = dict(self.master.getTopicTypes())
        me = rospy.get_name()
        return ({topic for topic, nodes in publishers if set(nodes) - {me}},
                {topic for topic, nodes in subscribers if set(nodes) - {me}}, types)

    def assert_topics(self, published, subscribed):
        """Each (topic, type) of `published` has a publisher, of `subscribed` a subscriber, with that type.

        The node sets its interface up one element after the other: the graph is read
        again until it is complete, or TIMEOUT has passed.
        """
        def missing():
            publishers, subscribers, _ = self.graph()
            return (['nobody publishes ' + topic for topic, _ in published if topic not in publishers] +
                    ['nobody subscribes to ' + topic for topic, _ in subscribed if topic not in subscribers])
        wait_for(lambda: not missing(), lambda: ', '.join(missing()), step=0.2)
        types = self.graph()[2]
        wrong = ['%s is %s, documented %s' % (topic, types.get(topic), kind) for topic, kind in published + subscribed
                 if types.get(topic) != kind]
        self.assertEqual(wrong, [])

    def test_services_exist_with_their_documented_types(self):
        wrong = []
        for name, kind in sorted(SERVICES.items()):
            try:
                rospy.wait_for_service(name, 5.0)
                actual = rosservice.get_service_type(name)
            except rospy.ROSException:
                actual = None
            if actual != kind:
                wrong.append('%s: %s, documented %s' % (name, actual or 'missing', kind))
        self.assertEqual(wrong, [])

    def test_topics_exist_with_their_documented_types(self):
        self.assert_topics(PUBLISHED, SUBSCRIBED)

    def test_action_servers_exist_with_their_documented_types(self):
        for namespace, action in ACTIONS:
            self.assert_topics(*action_topics(namespace, action))

    def test_bringup_default_controllers_are_loaded_with_their_documented_types(self):
        listing = rospy.ServiceProxy('/controller_manager/list_controllers', ListControllers)().controller
        loaded = {c.name: (c.state, c.type) for c in listing}
        for name in STARTED + STOPPED:
            self.assertIn(name, loaded)
            # Noetic's controller_manager lists a controller loaded but never started as `initialized`.
            self.assertEqual(loaded[name], ('running' if name in STARTED else 'initialized', CONTROLLER_TYPES[name]))
        # The simulation also loads the config's other controllers, stopped, so that any can be switched to.
        for name, (state, kind) in loaded.items():
            self.assertEqual(kind, CONTROLLER_TYPES.get(name), name)

    # -- semantics a client relies on, at the bring-up's defaults (no headless mode) -----------

    def controller_state(self, name):
        listing = rospy.ServiceProxy('/controller_manager/list_controllers', ListControllers)().controller
        return {c.name: c.state for c in listing}[name]

    def wait_program_running(self, running):
        wait_for(lambda: rospy.wait_for_message(HW + 'robot_program_running', Bool, TIMEOUT).data == running,
                 'robot_program_running %s' % running)

    def wait_controller(self, name, state):
        wait_for(lambda: self.controller_state(name) == state, '%s %s' % (name, state))

    def test_program_stopped_stops_commanding_controllers_until_it_plays_again(self):
        trigger = {name: rospy.ServiceProxy(HW + name, Trigger) for name in
                   ('dashboard/stop', 'dashboard/play', 'hand_back_control')}
        self.assertEqual(trigger['dashboard/stop']().message, 'Stopped')
        self.wait_program_running(False)
        # ur_control.launch's controller_stopper stops every controller but the read-only ones.
        self.wait_controller('scaled_pos_joint_traj_controller', 'stopped')
        self.assertEqual(self.controller_state('joint_state_controller'), 'running')
        # The hardware interface refuses to start a commanding controller without control, any strictness.
        switch = rospy.ServiceProxy('/controller_manager/switch_controller', SwitchController)
        self.assertFalse(switch(SwitchControllerRequest(start_controllers=['scaled_pos_joint_traj_controller'],
                                                        strictness=SwitchControllerRequest.BEST_EFFORT)).ok)
        response = trigger['hand_back_control']()
        self.assertEqual((response.success, response.message), (True, 'No control active. Nothing to do.'))
        self.assertEqual(trigger['dashboard/play']().message, 'Starting program')
        self.wait_program_running(True)
        self.wait_controller('scaled_pos_joint_traj_controller', 'running')

    def test_program_resent_after_a_script_hands_control_back(self):
        script = rospy.Publisher(HW + 'script_command', String, queue_size=1)
        wait_for_subscribers(script)
        script.publish(String(data='movej([0, -1.57, 1.57, -1.57, -1.57, 0], a=1.4, v=1.05)'))
        self.wait_program_running(False)
        response = rospy.ServiceProxy(HW + 'resend_robot_program', Trigger)()
        self.assertTrue(response.success, response.message)
        self.wait_program_running(True)
        self.wait_controller('scaled_pos_joint_traj_controller', 'running')

    def test_tf_frames(self):
        buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(buffer)
        for parent, child in TF_FRAMES:
            buffer.lookup_transform(parent, child, rospy.Time(0), rospy.Duration(TIMEOUT))


if __name__ == '__main__':
    rospy.init_node('ur_driver_interface_check')
    # ~cpu_load: one busy process per core beside the cell while the tests run, as on a shared CI runner.
    with cpu_load.CpuLoad() if rospy.get_param('~cpu_load', False) else cpu_load.NoLoad():
        rostest.rosrun('ur3_ft_gripper_description', 'ur_driver_interface_check', DocumentedInterfaceTest)
