#!/usr/bin/env python3
"""Force mode: press the tool on the table with a set force, as the robot's own force control does it.

URScript's force_mode has no ROS service in ur_robot_driver (ROS 1): users
send it as a program on script_command. This example does that, through the
real interfaces only (ur3_ft_gripper_description.clients), so it runs
unchanged on the real cell: it moves the tool over the table, zeroes the
FT 300 (rq_sensor's SET_ZERO), sends a program that presses along the tool's
z (pointing down) with each force in turn, reads rq_sensor's
robotiq_ft_wrench and the robot's own wrench while it holds, and hands
control back to External Control (the dashboard's play).

    roslaunch ur3_ft_gripper_description ur3_ft_gripper_bringup.launch sim:=true physics:=true
    rosrun ur3_ft_gripper_description force_mode_press.py
    rosrun ur3_ft_gripper_description force_mode_press.py --forces 10 20 40 --press 4

On the real robot keep a hand on the emergency stop: the tool goes down at
up to `--speed` until it meets the table.
"""
import argparse
import sys

from ur3_ft_gripper_description import clients

# Where the tool starts: gripper_tcp this high above the table top, over the default world's free table.
START_HEIGHT = 0.06
CLEAR_HEIGHT = 0.16
START_XY = (0.2986, 0.1123)
SETTLE = 3.0   # s of pressing before the force is read
MEASURE = 1.0  # s over which it is averaged
# s the program keeps pressing after the reading: this node sees the program start, and counts its time,
# a little late on a busy machine, and the reading must end before the tool lifts.
HOLD_AFTER = 2.0

PROGRAM = """def force_mode_press():
  force_mode(get_actual_tcp_pose(), [0, 0, 1, 0, 0, 0], [0, 0, {force}, 0, 0, 0], 2, [0.1, 0.1, {speed}, 0.17, 0.17, 0.17])
  sleep({seconds})
  end_force_mode()
  movel(pose_trans(get_actual_tcp_pose(), p[0, 0, -0.02, 0, 0, 0]), a=0.5, v=0.05)
end
"""


class ForceModePress(object):
    def __init__(self, rospy, say=print):
        self.rospy, self.say = rospy, say
        self.arm = clients.UrArm(rospy)
        self.sensor = clients.FT300(rospy)
        self.tool = clients.ToolKinematics(rospy)
        self.script = clients.UrScript(rospy)

    def start(self, x, y):
        """The tool above the table, the sensor zeroed there."""
        self.arm.move_along(self.tool.path_to(self.arm.joint_positions(), x, y, START_HEIGHT, CLEAR_HEIGHT))
        self.rospy.sleep(0.5)
        self.sensor.zero()

    def press(self, force, speed, seconds, sample=None):
        """Run the program with `force` (N); the steady readings (dict).

        `sample()`, if given, is called every 20 ms over the second the readings are averaged; its
        results come back as result['samples'] (a test reads the simulation's own contact force so).
        """
        self.script.run(PROGRAM.format(force=force, speed=speed, seconds=seconds + HOLD_AFTER))
        self.rospy.sleep(seconds - MEASURE)
        start = self.rospy.get_time()
        samples = []
        while sample is not None and self.rospy.get_time() < start + MEASURE:
            samples.append(sample())
            self.rospy.sleep(0.02)
        ft300 = self.sensor.mean_over(start, start + MEASURE)
        robot = self.script.wrench.mean_over(start, start + MEASURE)
        clients.wait_until(self.rospy, lambda: self.script.program_running is False and
                           self.rospy.get_time() > start + seconds + 3.0, 'the end of the program', 30.0)
        self.script.resume()
        return dict(force=force, ft300_fz=ft300[2], robot_fz=robot[2], ft300=ft300, robot=robot, samples=samples)


def main(argv=None):
    import rospy
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--forces', type=float, nargs='+', default=[10.0, 20.0, 40.0], help='N, along the tool')
    parser.add_argument('--speed', type=float, default=0.05, help='limit of the approach (m/s)')
    parser.add_argument('--press', type=float, default=SETTLE + MEASURE, help='s each force is held')
    parser.add_argument('--at', type=float, nargs=2, default=START_XY, metavar=('X', 'Y'),
                        help='where over the table (m, base_link)')
    args = parser.parse_args(rospy.myargv(argv if argv is not None else sys.argv)[1:])
    rospy.init_node('force_mode_press', anonymous=True)
    try:
        press = ForceModePress(rospy)
        for force in args.forces:
            press.start(*args.at)
            result = press.press(force, args.speed, args.press)
            print('force_mode %5.1f N: FT 300 fz %6.2f N, robot wrench fz %6.2f N'
                  % (force, result['ft300_fz'], result['robot_fz']))
    except clients.CellError as exc:
        sys.exit('force_mode_press: %s' % exc)


if __name__ == '__main__':
    main()
