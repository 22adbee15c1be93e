"""ur_robot_driver's dashboard client (~dashboard/*) over the simulated robot.

Each service sends the Dashboard Server command the driver's client sends,
and answers from the simulated robot's reply (robot_state.RobotState.dashboard)
with the driver's success rule: the reply must match what the driver expects.
"""

import re

from std_srvs.srv import Trigger
from ur_dashboard_msgs import srv as dash_srv
from ur_dashboard_msgs.msg import ProgramState, RobotMode, SafetyMode


# What ur_robot_driver's dashboard services send, and the answer each expects for success.
DASHBOARD_TRIGGERS = {
    'power_on': ('power on', r'Powering on'),
    'power_off': ('power off', r'Powering off'),
    'brake_release': ('brake release', r'Brake releasing'),
    'play': ('play', r'Starting program'),
    'pause': ('pause', r'Pausing program'),
    'stop': ('stop', r'Stopped'),
    'unlock_protective_stop': ('unlock protective stop', r'Protective stop releasing'),
    'restart_safety': ('restart safety', r'Restarting safety'),
    'close_popup': ('close popup', r'closing popup'),
    'close_safety_popup': ('close safety popup', r'closing safety popup'),
    'shutdown': ('shutdown', r'Shutting down'),
    'clear_operational_mode': ('clear operational mode', r'No longer controlling the operational mode'),
}


def answer_matches(answer, expected):
    return re.match(expected, answer) is not None


class DashboardServices(object):
    """Advertises the ~dashboard/* services of node `rospy` for `robot`, guarded by `lock`."""

    def __init__(self, rospy, robot, lock, e_series):
        self.robot, self.lock = robot, lock
        for name, (command, expected) in DASHBOARD_TRIGGERS.items():
            rospy.Service('~dashboard/' + name, Trigger, self._trigger(command, expected))
        rospy.Service('~dashboard/connect', Trigger, lambda req: (True, 'Connected: Universal Robots Dashboard '
                                                                    'Server (simulated)'))
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
        if e_series:
            rospy.Service('~dashboard/is_in_remote_control', dash_srv.IsInRemoteControl, lambda req: (
                self.command('is in remote control'), True, True))

    def command(self, command):
        """The robot's reply to one Dashboard Server command."""
        with self.lock:
            return self.robot.dashboard(command)

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
            mode = self.robot.robot_mode
            answer = self.robot.dashboard('robotmode')
        return RobotMode(mode=getattr(RobotMode, mode)), answer, True

    def _get_safety_mode(self, request):
        with self.lock:
            mode = self.robot.safety_mode
            answer = self.robot.dashboard('safetymode')
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
