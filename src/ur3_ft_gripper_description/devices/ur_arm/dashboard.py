"""ur_robot_driver's dashboard client (~dashboard/*) over the simulated robot.

Each service sends the Dashboard Server command the driver's client sends,
and answers from the simulated robot's reply (core.ArmCore.dashboard) with
the driver's success rule: the reply must match what the driver expects
(robot_state.DASHBOARD_TRIGGERS).
"""

from std_srvs.srv import Trigger
from ur_dashboard_msgs import srv as dash_srv
from ur_dashboard_msgs.msg import ProgramState, RobotMode, SafetyMode

from .robot_state import DASHBOARD_TRIGGERS, answer_matches


class DashboardServices(object):
    """Advertises the ~dashboard/* services of node `rospy` for `core` (an ArmCore), guarded by `lock`."""

    def __init__(self, rospy, core, lock):
        self.core, self.lock = core, lock
        for name, (command, expected) in DASHBOARD_TRIGGERS.items():
            rospy.Service('~dashboard/' + name, Trigger, self._trigger(command, expected))
        rospy.Service('~dashboard/connect', Trigger,
                      lambda req: (True, 'Connected: Universal Robots Dashboard Server (simulated)'))
        rospy.Service('~dashboard/add_to_log', dash_srv.AddToLog, lambda req: self._answer(
            'addToLog ' + req.message, '(Added log message|No log message to add)$'))
        rospy.Service('~dashboard/popup', dash_srv.Popup, lambda req: self._answer(
            'popup ' + req.message, 'showing popup'))
        rospy.Service('~dashboard/load_program', dash_srv.Load, lambda req: self._answer(
            'load ' + req.filename, 'Loading program: .+'))
        rospy.Service('~dashboard/load_installation', dash_srv.Load, lambda req: self._answer(
            'load installation ' + req.filename, 'Loading installation: .+'))
        rospy.Service('~dashboard/raw_request', dash_srv.RawRequest, lambda req: (self.command(req.query),))
        rospy.Service('~dashboard/quit', dash_srv.GetLoadedProgram, lambda req: (
            self.command('quit'), '', True))
        rospy.Service('~dashboard/get_loaded_program', dash_srv.GetLoadedProgram, self._get_loaded_program)
        rospy.Service('~dashboard/get_robot_mode', dash_srv.GetRobotMode, self._get_robot_mode)
        rospy.Service('~dashboard/get_safety_mode', dash_srv.GetSafetyMode, self._get_safety_mode)
        rospy.Service('~dashboard/program_running', dash_srv.IsProgramRunning, self._program_running)
        rospy.Service('~dashboard/program_saved', dash_srv.IsProgramSaved, self._program_saved)
        rospy.Service('~dashboard/program_state', dash_srv.GetProgramState, self._program_state)
        if core.software.e_series:  # ROS_INTERFACE.md: "only available on e-Series models"
            rospy.Service('~dashboard/is_in_remote_control', dash_srv.IsInRemoteControl, lambda req: (
                self.command('is in remote control'), True, True))

    def command(self, command):
        """The robot's reply to one Dashboard Server command."""
        with self.lock:
            return self.core.dashboard(command)

    def _answer(self, command, expected):
        answer = self.command(command)
        return answer, answer_matches(answer, expected)

    def _trigger(self, command, expected):
        def call(request):
            answer = self.command(command)
            return answer_matches(answer, expected), answer
        return call

    def _get_loaded_program(self, request):
        answer = self.command('get loaded program')
        name = answer[len('Loaded program: '):] if answer.startswith('Loaded program: ') else ''
        return answer, name, bool(name)

    def _get_robot_mode(self, request):
        with self.lock:
            mode = self.core.robot.robot_mode
            answer = self.core.dashboard('robotmode')
        return RobotMode(mode=getattr(RobotMode, mode)), answer, True

    def _get_safety_mode(self, request):
        with self.lock:
            mode = self.core.robot.safety_mode
            answer = self.core.dashboard('safetymode')
        return SafetyMode(mode=getattr(SafetyMode, mode)), answer, True

    def _program_running(self, request):
        answer = self.command('running')
        return answer, answer.endswith('true'), True

    def _program_saved(self, request):
        answer = self.command('isProgramSaved')
        saved, _, name = answer.partition(' ')
        return answer, name, saved == 'true', True

    def _program_state(self, request):
        answer = self.command('programState')
        state, _, name = answer.partition(' ')
        return ProgramState(state=state), name, answer, True
