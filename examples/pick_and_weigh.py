#!/usr/bin/env python3
"""Pick and weigh: grasp an object with the 2F-140, lift it, weigh it on the FT 300, put it back.

Through the real drivers' interfaces only (ur3_ft_gripper_description.clients),
so it runs unchanged on the real cell: ur_robot_driver's
scaled_pos_joint_traj_controller for the arm, Robotiq's register topics for
the gripper, rq_sensor's robotiq_ft_wrench and SET_ZERO for the sensor. Where
the object stands, how tall and heavy it is, comes from a world file (the
physics cell's, config/worlds/default.yaml by default).

    roslaunch ur3_ft_gripper_description ur3_ft_gripper_bringup.launch sim:=true physics:=true
    rosrun ur3_ft_gripper_description pick_and_weigh.py                  # the default world's block
    rosrun ur3_ft_gripper_description pick_and_weigh.py --object can

It moves the gripper above the object, zeroes the sensor there, goes down,
closes on the object (gOBJ 2), lifts it back above, weighs it (the mean force
over a second, after SET_ZERO: the object's weight alone), puts it down where
it was and opens. Each step prints one line; the weight's reads
"weighed <kg> kg (<N> N), the world file says <kg> kg: <+-%> %".
"""
import argparse
import sys

from transforms3d.euler import quat2euler

from ur3_ft_gripper_description import clients
from ur3_ft_gripper_description.devices import gripper_model, sim_params
from ur3_ft_gripper_description.devices.physics.arm_cell import default_world_file
from ur3_ft_gripper_description.devices.physics.world import load_world

# Above the object's top before and after the grasp (m), and how far below it gripper_tcp goes to grasp
# (m): the pads, 70 mm long, then hold the object's upper part.
CLEARANCE = 0.05
GRASP_DEPTH = 0.04
# The pads reach lower as they close (the 2F-140's linkage): 11 mm below gripper_tcp open, 35 mm closed.
# So gripper_tcp stays this high over the table while grasping: the pads' lower edges 10 mm clear of it.
GRASP_FLOOR = 0.045
# From one place to the next the tool passes this high (gripper_tcp, m over the table): the open pads
# clear objects up to 120 mm tall, as the default world's, and the UR3 reaches 0.4 m out at it.
CLEAR_HEIGHT = 0.16
# Settling time after a move before the sensor is read, and how long its readings are averaged (s).
SETTLE, AVERAGE = 1.0, 1.0


def register_scale():
    """The 2F-140's register <-> gap mapping of config/sim_devices.yaml (measure your unit's)."""
    spec = gripper_model.load_gripper_spec(sim_params.default_devices_file(), ('stroke', 'gpo_open', 'gpo_closed'))
    return gripper_model.RegisterScale(spec['stroke'], spec['gpo_open'], spec['gpo_closed'])


def target_of(world_file, name):
    """(x, y, top z, yaw, width between the pads, mass) of object `name` of a world file."""
    world = load_world(world_file)
    solid = world.by_name(name)
    if solid.shape == 'mesh':
        raise clients.CellError('%s is a mesh: this example takes a box or a cylinder' % name)
    x, y, z = solid.position
    yaw = quat2euler(solid.quaternion, axes='sxyz')[2]
    if solid.shape == 'box':
        width, height = solid.size[1], solid.size[2]
    else:
        width, height = solid.size[0], solid.size[1]
    return x, y, z + height / 2.0, yaw, width, solid.mass


class PickAndWeigh(object):
    def __init__(self, rospy, say=print):
        self.rospy, self.say = rospy, say
        self.arm = clients.UrArm(rospy)
        self.gripper = clients.Gripper2F(rospy)
        self.sensor = clients.FT300(rospy)
        self.tool = clients.ToolKinematics(rospy)
        self.scale = register_scale()
        self.above = self.grasp = None

    def pick(self, x, y, top, yaw):
        """Above the object, zero the sensor, down, close: the gap between the pads (m) from gPO."""
        if self.gripper.status.gSTA != 3:
            self.gripper.activate()
        self.gripper.go(0)
        path = self.tool.path_to(self.arm.joint_positions(), x, y, top + CLEARANCE, CLEAR_HEIGHT, yaw)
        self.above = path[-1]
        self.grasp = self.tool.joints_for(self.tool.tool_down(x, y, max(top - GRASP_DEPTH, GRASP_FLOOR), yaw),
                                          self.above)
        self.arm.move_along(path)
        self.rospy.sleep(SETTLE)
        self.sensor.zero()
        self.say('above the object at (%.3f, %.3f), sensor zeroed' % (x, y))
        self.arm.move_steadily(self.grasp, speed=0.2)
        status = self.gripper.go(255, speed=128, force=150)
        if status.gOBJ != clients.Gripper2F.OBJECT_CLOSING:
            raise clients.CellError('closing found no object (gOBJ %d, gPO %d)' % (status.gOBJ, status.gPO))
        width = self.scale.opening(status.gPO)
        self.say('grasped: gOBJ %d, gPO %d: %.1f mm between the pads' % (status.gOBJ, status.gPO, 1e3 * width))
        return width

    def weigh(self):
        """Lift the object back above its place and weigh it: (mass kg, force N)."""
        self.arm.move_steadily(self.above, speed=0.2)
        self.rospy.sleep(SETTLE)
        force = clients.force_norm(self.sensor.mean(AVERAGE))
        return force / clients.STANDARD_GRAVITY, force

    def put_down(self):
        """Back where it was, open, and up again: the gripper's last status."""
        self.arm.move_steadily(self.grasp, speed=0.2)
        status = self.gripper.go(0)
        self.arm.move_steadily(self.above, speed=0.2)
        self.say('put down and opened: gOBJ %d' % status.gOBJ)
        return status


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--world', default=default_world_file(), help='the world file (default: the default world)')
    parser.add_argument('--object', default='block', help="the object's name in the world file (default: block)")
    import rospy
    args = parser.parse_args(rospy.myargv(argv if argv is not None else sys.argv)[1:])
    rospy.init_node('pick_and_weigh', anonymous=True)
    try:
        x, y, top, yaw, width, mass = target_of(args.world, args.object)
        cell = PickAndWeigh(rospy)
        cell.pick(x, y, top, yaw)
        weighed, force = cell.weigh()
        cell.say('weighed %.4f kg (%.3f N), the world file says %.4f kg: %+.2f %%' % (
            weighed, force, mass, 100.0 * (weighed - mass) / mass))
        cell.put_down()
    except (clients.CellError, KeyError) as exc:
        print('pick_and_weigh: %s' % (exc if not isinstance(exc, KeyError) else
                                      'no object %s in %s' % (exc, args.world)), file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
