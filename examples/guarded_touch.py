#!/usr/bin/env python3
"""Guarded touch: move the tool down until the FT 300 feels the table, then stop and report.

The guarded move users write first, through the real drivers' interfaces only
(ur3_ft_gripper_description.clients), so it runs unchanged on the real cell:
controller_manager's switch to ur_robot_driver's twist_controller, a twist
down at 20 mm/s on twist_controller/command, rq_sensor's robotiq_ft_wrench
after SET_ZERO. It stops (a zero twist) at the first reading of 10 N, then
reports how far the force and the tool went past that (the overshoot) and the
force once the arm stands still; then it backs off and returns to
scaled_pos_joint_traj_controller.

    roslaunch ur3_ft_gripper_description ur3_ft_gripper_bringup.launch sim:=true physics:=true
    rosrun ur3_ft_gripper_description guarded_touch.py
    rosrun ur3_ft_gripper_description guarded_touch.py --speed 0.01 --limit 5

It starts with the gripper open, its pads about 70 mm over the table, where
the arm's start pose has them (--at X Y: elsewhere, in base_link).
"""
import argparse
import sys

from ur3_ft_gripper_description import clients

# The tool's start: gripper_tcp this high above the table top (z = 0 of the world file); the open pads'
# lower edges are 11 mm below it.
START_HEIGHT = 0.08
# On the way there the tool passes this high: the open pads clear objects up to 120 mm tall.
CLEAR_HEIGHT = 0.16
# Where the arm's start pose holds gripper_tcp (m, base_link): over the default world's free table.
START_XY = (0.2986, 0.1123)
TWIST_RATE = 100.0  # Hz, as the force readings come
STILL = 1.0         # s the arm stands before the steady force is read, and then averaged


class GuardedTouch(object):
    def __init__(self, rospy, say=print):
        self.rospy, self.say = rospy, say
        self.arm = clients.UrArm(rospy)
        self.gripper = clients.Gripper2F(rospy)
        self.sensor = clients.FT300(rospy)
        self.tool = clients.ToolKinematics(rospy)

    def tool_height(self):
        return float(self.tool.tool_pose(self.arm.joint_positions())[2, 3])

    def start(self, x, y, height=START_HEIGHT):
        """`height` (m, gripper_tcp's) above the table with the gripper open, on the twist controller, the
        sensor zeroed."""
        if self.gripper.status.gSTA != 3:
            self.gripper.activate()
        self.gripper.go(0)
        self.arm.move_along(self.tool.path_to(self.arm.joint_positions(), x, y, height, CLEAR_HEIGHT))
        self.arm.only('twist_controller', [clients.TRAJECTORY_CONTROLLER])
        self.rospy.sleep(0.5)
        self.sensor.zero()

    def touch(self, speed, limit, timeout=20.0):
        """Down at `speed` (m/s) until |F| >= `limit` (N); the figures once the arm stands still (dict)."""
        rate = self.rospy.Rate(TWIST_RATE)
        end = self.rospy.get_time() + timeout
        start_height, start = self.tool_height(), self.rospy.get_time()
        while True:
            self.arm.twist(vz=-speed)
            detected = clients.force_norm(self.sensor.latest())
            if detected >= limit:
                break
            if self.rospy.get_time() > end:
                self.arm.twist()
                raise clients.CellError('no %g N of contact within %g s' % (limit, timeout))
            # A contact the FT 300 does not see (an arm link's) can stop the robot: then say so, the twist
            # zeroed first (the controller holds the last one, to go on after the stop is released).
            self.stop_if_unsafe()
            rate.sleep()
        self.arm.twist()
        detected_height = self.tool_height()
        self.rospy.sleep(STILL)
        # The peak: the reading that stopped the arm or any later one (an impact rings on a stiff surface).
        forces = [clients.force_norm(w) for w in self.sensor.since(start)]
        peak = max(forces[next(i for i, f in enumerate(forces) if f >= limit):])
        stopped_height = self.tool_height()
        steady = self.sensor.mean(STILL)
        return dict(limit=limit, speed=speed, travel=start_height - detected_height, detected_force=detected,
                    peak_force=peak, overshoot_force=peak - limit, overshoot_travel=detected_height - stopped_height,
                    steady_force=clients.force_norm(steady), steady_wrench=steady)

    def stop_if_unsafe(self):
        try:
            self.arm.check_safety()
        except clients.CellError:
            self.arm.twist()
            raise

    def back_off(self, speed):
        """Up until the force is gone and 10 mm more, then back on the trajectory controller."""
        rate = self.rospy.Rate(TWIST_RATE)
        end = self.rospy.get_time() + 5.0 + 0.01 / speed
        clear = None
        while self.rospy.get_time() < end:
            self.arm.twist(vz=speed)
            if clear is None and clients.force_norm(self.sensor.latest()) < 1.0:
                clear = self.rospy.get_time()
            if clear is not None and self.rospy.get_time() - clear > 0.01 / speed:
                break
            self.stop_if_unsafe()
            rate.sleep()
        self.arm.twist()
        self.rospy.sleep(0.2)
        self.arm.only(clients.TRAJECTORY_CONTROLLER, ['twist_controller'])

    def report(self, figures):
        self.say('contact: %.1f N after %.1f mm at %.0f mm/s; stopped at the first reading of %g N or more' % (
            figures['detected_force'], 1e3 * figures['travel'], 1e3 * figures['speed'], figures['limit']))
        self.say('overshoot: %.1f N over the limit (peak %.1f N), %.2f mm further down' % (
            figures['overshoot_force'], figures['peak_force'], 1e3 * figures['overshoot_travel']))
        self.say('steady force, standing still: %.2f N' % figures['steady_force'])


def main(argv=None):
    import rospy
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--speed', type=float, default=0.02, help='down at this speed (m/s, default 0.02)')
    parser.add_argument('--limit', type=float, default=10.0, help='stop at this force (N, default 10)')
    parser.add_argument('--at', type=float, nargs=2, default=START_XY, metavar=('X', 'Y'),
                        help='where to touch (m, base_link; default: below the start pose\'s tool)')
    args = parser.parse_args(rospy.myargv(argv if argv is not None else sys.argv)[1:])
    rospy.init_node('guarded_touch', anonymous=True)
    try:
        cell = GuardedTouch(rospy)
        cell.start(*args.at)
        figures = cell.touch(args.speed, args.limit)
        cell.report(figures)
        cell.back_off(args.speed)
    except clients.CellError as exc:
        print('guarded_touch: %s' % exc, file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
