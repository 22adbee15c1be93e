"""The publish loop both simulated devices run: a step at a fixed rate until shutdown."""

import gc

from ur3_ft_gripper_description import master_watch


def run_at_rate(rospy, hz, step, on_time_jump=None):
    """Call `step()` `hz` times a second until rospy shuts down; returns the exit status.

    Also keeps the node registered across a master restart (master_watch), and
    calls `on_time_jump()` when ROS time jumps back (a bag or simulation restarted).
    """
    master = master_watch.start(rospy)
    # Everything made so far (modules, message classes, the model) lives as long as
    # the node: out of the collector's reach, a full collection no longer stops
    # the loop for ~20 ms (more on a loaded machine), which showed as message gaps.
    gc.freeze()
    rate = rospy.Rate(hz)
    while not rospy.is_shutdown():
        step()
        try:
            rate.sleep()
        except rospy.ROSTimeMovedBackwardsException:
            if on_time_jump is not None:
                on_time_jump()
        except rospy.ROSInterruptException:
            break
    return master.exit_status
