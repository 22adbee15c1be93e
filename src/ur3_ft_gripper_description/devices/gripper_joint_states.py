"""finger_joint from a 2F-140's status registers, for the real gripper and the simulated one.

Robotiq's drivers publish no joint states, so a model's fingers never move.
This node subscribes ``Robotiq2FGripperRobotInput`` (from
Robotiq2FGripperRtuNode.py / TcpNode.py or from gripper_sim) and publishes
``gripper/joint_states`` (sensor_msgs/JointState with the one joint
``<prefix>finger_joint``) for joint_state_publisher's ``source_list``; the
mimic joints follow it there.

gPO -> opening -> angle:
  * opening: gripper_model.RegisterScale, linear between ~gpo_open (the full
    0.140 m stroke) and ~gpo_closed (0 m); these differ per unit: measure
    yours (config/sim_devices.yaml says how and gives the defaults);
  * angle: the model's own finger kinematics (gripper_model.GripperKinematics,
    from ``robot_description``), so the pads in TF are that far apart. The
    model's pads open only ~0.1285 m: any wider opening shows as 0 rad.

Its private parameters are declared in PARAMETERS below (their reference:
doc/node_parameters.md).
"""

from ur3_ft_gripper_description.devices import gripper_model, node_loop, sim_params


PARAMETERS = (
    sim_params.PREFIX,
    sim_params.Param('~gpo_open', sim_params.StartupDefault('the gripper\'s `gpo_open` in ~devices_file'),
                     'gPO of this unit fully open (the full stroke); measure yours (config/sim_devices.yaml says '
                     'how)', sim_params.number(minimum=0.0)),
    sim_params.Param('~gpo_closed', sim_params.StartupDefault('the gripper\'s `gpo_closed` in ~devices_file'),
                     'gPO of this unit fully closed (0 m)', sim_params.number(minimum=0.0)),
    sim_params.DEVICES_FILE,
)


def scale_from_params(get_param):
    """The unit's RegisterScale from ~gpo_open, ~gpo_closed and ~devices_file; ParamError if bad."""
    spec = sim_params.from_devices_file(get_param, PARAMETERS, lambda path: gripper_model.load_gripper_spec(
        path, ('stroke', 'gpo_open', 'gpo_closed')))
    gpo_open = sim_params.read(get_param, PARAMETERS, '~gpo_open', default=spec['gpo_open'])
    gpo_closed = sim_params.read(get_param, PARAMETERS, '~gpo_closed', default=spec['gpo_closed'])
    if not gpo_open < gpo_closed <= 255:
        raise sim_params.ParamError('~gpo_open=%g, ~gpo_closed=%g: need 0 <= gpo_open < gpo_closed '
                                    '<= 255 (gPO of this unit fully open, fully closed)'
                                    % (gpo_open, gpo_closed))
    return gripper_model.RegisterScale(float(spec['stroke']), gpo_open, gpo_closed)


class JointTable(object):
    """finger_joint angle for each of the 256 values of gPO."""

    def __init__(self, fingers, scale):
        self.joint_name = fingers.joint_name
        self.angles = [fingers.angle(scale.opening(gpo)) for gpo in range(256)]

    def angle(self, gpo):
        return self.angles[min(max(int(gpo), 0), 255)]


def run(rospy):
    """The node. Returns the exit status."""
    from robotiq_2f_gripper_control.msg import Robotiq2FGripper_robot_input
    from sensor_msgs.msg import JointState

    name = rospy.get_name()
    try:
        prefix = sim_params.read(rospy.get_param, PARAMETERS, '~prefix')
        scale = scale_from_params(rospy.get_param)
    except sim_params.ParamError as exc:
        rospy.logfatal('%s: bad parameter %s', name, exc)
        return 1
    description = node_loop.wait_for_param(rospy, 'robot_description', '%s: waiting for the '
                                            'robot_description parameter: the finger kinematics '
                                            'come from the model (load_ur3_ft_gripper.launch)' % name)
    if description is None:
        return 0
    try:
        fingers = gripper_model.GripperKinematics(description, prefix=prefix)
    except ValueError as exc:
        rospy.logfatal('%s: robot_description has no usable 2F-140 (%s); check ~prefix', name, exc)
        return 1
    table = JointTable(fingers, scale)
    # Two seconds of the 50 Hz status, both ways: a node or subscriber served late (a busy machine, the
    # cell at real_time_factor 0) gets every state late, none dropped from a queue.
    publisher = rospy.Publisher('gripper/joint_states', JointState, queue_size=100)
    gate = node_loop.PublishGate(rospy)

    def on_status(msg):
        state = JointState()
        state.header.stamp = rospy.Time.now()
        state.name = [table.joint_name]
        state.position = [table.angle(msg.gPO)]
        gate.call(publisher.publish, state)

    rospy.Subscriber('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input, on_status,
                     queue_size=100)
    rospy.loginfo('%s: %s from gPO (%g open .. %g closed) on gripper/joint_states', name,
                  table.joint_name, scale.gpo_open, scale.gpo_closed)
    return node_loop.spin(rospy)


def main():
    return node_loop.main('gripper_joint_states', run)
