"""A node whose loop (node_loop.run_at_rate) publishes every cycle, with rospy's shutdown held
open for a second after its topics close: the window in which a publish() fails with
"publish() to a closed topic". A loop that still runs then prints a traceback; node_loop's
must not. Run by test_master_restart.py with the package's workspace sourced."""
import sys
import time

from std_msgs.msg import UInt32

from ur3_ft_gripper_description.devices import node_loop

HOLD_OPEN = 1.0  # s, against the microseconds of the real window


def run(rospy):
    publisher = rospy.Publisher('count', UInt32, queue_size=10)
    # rospy's registration clean-up, which closes the topics, was added at init_node: this
    # pre-shutdown hook runs after it, before rospy's is_shutdown() turns True.
    rospy.core.add_preshutdown_hook(lambda reason: time.sleep(HOLD_OPEN))
    count = UInt32()

    def step():
        count.data += 1
        publisher.publish(count)

    return node_loop.run_at_rate(rospy, 200, step)


if __name__ == '__main__':
    sys.exit(node_loop.main('slow_closing_publisher', run))
