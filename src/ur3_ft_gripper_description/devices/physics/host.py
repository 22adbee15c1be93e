"""The physics cell's host in the arm's node: the cell, its link server and its real-time factor on /diagnostics.

With ``~physics`` the simulated arm's node (``ur_hardware_interface``) makes
one ``CellHost``: it builds the cell of robot_description in ``~world_file``
(``arm_cell``), serves it to the FT 300 and 2F-140 nodes through the private
link (``link``), and after each control cycle measures how fast simulated
time runs against the wall clock (``pacing``), published on ``/diagnostics``
(diagnostic_msgs/DiagnosticArray) once a wall-clock second, with one warning
when the machine cannot keep the pace asked for.

The node's control loop steps the cell through the arm's joint motion
(``ur_arm/physics_joints.py``) and keeps the clock (``devices/sim_clock.py``,
``node_loop.run_as_clock``); this module imports nothing of the arm's.
"""

import time

from . import link
from .arm_cell import cell_for_arm
from .pacing import RealTimeMeter


class CellHost(object):
    """The physics cell of the node `rospy` runs: built, served on the link, measured.

    `settings` has the arm's ur_type, prefix and initial position; `lock` is
    the one the node's control cycle holds while it steps the cell.
    `pace` is the real-time factor the loop is paced to (None: the wall clock).
    """

    DIAGNOSTICS_PERIOD = 1.0  # wall-clock s

    def __init__(self, rospy, get_param, settings, lock, pace=None, wall=time.monotonic):
        from diagnostic_msgs.msg import DiagnosticArray
        self.rospy = rospy
        self.cell = cell_for_arm(get_param, settings)
        self.world = self.cell.world.path
        self.meter = RealTimeMeter(slow=0.9 * pace if pace else 0.9, paced_to=pace)
        self._wall = wall
        self.address = link.node_cell_address(rospy)[0]
        self.server = link.CellServer(self.cell, self.address, lock=lock)
        rospy.on_shutdown(self.server.close)
        self.diagnostics = rospy.Publisher('/diagnostics', DiagnosticArray, queue_size=10)
        self.next_report = 0.0
        self.cycles = 0
        rospy.loginfo('%s: physics (MuJoCo) with the world %s; the FT 300 and 2F-140 nodes reach the cell at %s'
                      % (rospy.get_name(), self.world, self.address))

    def after_step(self):
        """Once per control cycle, after the cell stepped: the real-time factor, and its report once a second."""
        wall = self._wall()
        self.meter.add(wall, self.cell.time)
        self.cycles += 1
        warning = self.meter.slow_warning()
        if warning and not self.rospy.core.is_shutdown_requested():  # a shutdown stalls the loop: no warning
            self.rospy.logwarn('%s: %s' % (self.rospy.get_name(), warning))
        if wall >= self.next_report:
            self.next_report = wall + self.DIAGNOSTICS_PERIOD
            self._report()

    def _report(self):
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
        factor = self.meter.factor()
        slow = factor is not None and self.meter.full() and factor < self.meter.slow
        status = DiagnosticStatus(
            level=DiagnosticStatus.WARN if slow else DiagnosticStatus.OK,
            name='%s: physics' % self.rospy.get_name(), hardware_id='physics cell (MuJoCo)',
            message=('real-time factor %.2f' % factor) if factor is not None else 'starting',
            values=[KeyValue(key='real-time factor', value='%.3f' % factor if factor is not None else ''),
                    KeyValue(key='simulated time (s)', value='%.3f' % self.cell.time),
                    KeyValue(key='control cycles', value=str(self.cycles)),
                    KeyValue(key='world', value=self.world)])
        message = DiagnosticArray(status=[status])
        message.header.stamp = self.rospy.Time.now()
        self.diagnostics.publish(message)
