"""The UR controller box's modes, program, speed slider and IO, and its dashboard server, without ROS.

Robot modes (ur_dashboard_msgs/RobotMode names) go POWER_OFF -> BOOTING ->
POWER_ON -> IDLE on "power on", IDLE -> RUNNING on "brake release" (which
powers on first when needed), anything -> POWER_OFF on "power off". The
transitions take `transition_time` seconds each, much less than the real
robot's, so that tests and users do not wait for a simulated boot.

The External Control program runs (robot_program_running) when the robot
is RUNNING and either "play" started a loaded program that holds it, or
headless mode sent it (resend_robot_program). Powering off, "stop", a
script sent to script_command, hand_back_control, all end it.

A protective stop (reported by the joints, e.g. a collision in a physics
engine) sets the safety mode PROTECTIVE_STOP and pauses the program, as on
the robot; ur_robot_driver's features.md: "continue trajectories after
protective stop: yes", so a paused External Control program resumes with
"play" once "unlock protective stop" has cleared the stop, which the
Dashboard Server refuses in the first 5 s.

The dashboard answers are the UR dashboard server's (Universal Robots'
"Dashboard server" manual, e-Series/CB3): the driver's Trigger services
succeed when the answer matches what it expects.
"""

import collections
import re
import time

from . import dashboard_commands
from .registers import Registers


# Robot mode names in ur_dashboard_msgs/RobotMode order of start-up.
POWER_OFF, BOOTING, POWER_ON, IDLE, RUNNING = 'POWER_OFF', 'BOOTING', 'POWER_ON', 'IDLE', 'RUNNING'
MODE_ORDER = (POWER_OFF, BOOTING, POWER_ON, IDLE, RUNNING)
SAFETY_NORMAL, PROTECTIVE_STOP = 'NORMAL', 'PROTECTIVE_STOP'
SELECTABLE_MODES = (POWER_OFF, IDLE, RUNNING)
EXTERNAL_CONTROL = 'external_control.urp'
PLAYING, PAUSED, STOPPED = 'PLAYING', 'PAUSED', 'STOPPED'
# Dashboard Server manual, "unlock protective stop": refused until 5 s after the stop.
UNLOCK_DELAY = 5.0
UNLOCK_TOO_EARLY = ('Cannot unlock protective stop until 5s after occurrence. Always inspect cause of protective '
                    'stop before unlocking')
# The robot's log (textmsg, popup, addToLog, protective stops) as the simulation keeps it: the
# latest entries only, each cut to a length. Nothing but the node's rosout reads it back, so it
# needs only the recent history; 1000 entries of at most 1000 characters stay within ~1 MB
# however long a program logs in a loop (the soak holds the node's growth under 5 MB).
LOG_ENTRIES = 1000
LOG_ENTRY_CHARACTERS = 1000

# A dashboard command's answer when its argument is not one the robot knows: the robot's "could not understand".
_NOT_UNDERSTOOD = object()

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
# The same by the command line, for robot_state_helper's calls of those services.
EXPECTED_ANSWER = {command: expected for command, expected in DASHBOARD_TRIGGERS.values()}


# Digital outputs: 8 standard (0-7), 8 configurable (8-15), 2 tool (16-17); flags: none
# reported; analog: the 2 standard inputs and 2 standard outputs, which is all the driver's
# io_states carries (the tool's analog inputs are in its tool_data).
DIGITAL_PINS = 18
ANALOG_OUTPUTS = 2
ANALOG_INPUTS = 2
TOOL_VOLTAGES = (0, 12, 24)


def answer_matches(answer, expected):
    return re.match(expected, answer) is not None


class RobotState(object):
    """Modes, program, slider, IO, payload, safety; `step(dt)` lets timed transitions happen.

    `software`: the model's software.ControllerSoftware (which dashboard
    commands exist, what "PolyScope version" answers).
    """

    def __init__(self, software, robot_mode=RUNNING, program_running=True, headless=False,
                 transition_time=0.5, programs=(EXTERNAL_CONTROL,)):
        self.software = software
        self.robot_mode = robot_mode
        self.safety_mode = SAFETY_NORMAL
        self.headless = headless
        self.transition_time = float(transition_time)
        self.programs = list(programs)
        self.loaded_program = None if headless else EXTERNAL_CONTROL
        self.program_state = STOPPED
        self.external_control_running = False
        self.speed_slider = 1.0
        self.digital_out = [False] * DIGITAL_PINS
        self.digital_in = [False] * DIGITAL_PINS
        self.analog_out = [0.0] * ANALOG_OUTPUTS
        self.analog_in = [0.0] * ANALOG_INPUTS
        self.tool_voltage = 0
        self.payload = (0.0, (0.0, 0.0, 0.0))
        self.registers = Registers()  # shared by programs and RTDE clients
        self.log = collections.deque(maxlen=LOG_ENTRIES)
        self.popup = None
        self.dashboard_commands = dashboard_commands.read()
        self.user_role = 'NONE'  # CB3: no user role restriction
        self.operational_mode = None  # e-Series: PolyScope's, not set over the dashboard
        self.flight_reports = 0
        self._target = None        # robot mode a transition is heading for
        self._timer = 0.0
        self._stopped_for = 0.0    # s since the protective stop
        if program_running and robot_mode == RUNNING:
            self.program_state = PLAYING
            self.external_control_running = True

    # -- derived ---------------------------------------------------------------

    @property
    def program_running(self):
        """robot_program_running: the External Control node runs, i.e. ROS may command."""
        return self.external_control_running and self.robot_mode == RUNNING

    @property
    def moving_allowed(self):
        """The arm may move: running, no safety stop, a program playing (not paused)."""
        return self.robot_mode == RUNNING and self.safety_mode == SAFETY_NORMAL and self.program_state == PLAYING

    def speed_scaling(self):
        """The slider while a program plays, 0 otherwise (a stopped or paused one does not move)."""
        return self.speed_slider if self.moving_allowed else 0.0

    def add_log(self, text):
        self.log.append(str(text)[:LOG_ENTRY_CHARACTERS])

    # -- time ------------------------------------------------------------------

    def step(self, dt):
        """Advance a pending power-on / brake-release transition, and a protective stop's clock, by dt s."""
        if self.safety_mode == PROTECTIVE_STOP:
            self._stopped_for += dt
        if self._target is None:
            return
        self._timer += dt
        if self._timer < self.transition_time:
            return
        self._timer = 0.0
        here = MODE_ORDER.index(self.robot_mode)
        if here < MODE_ORDER.index(self._target):
            self.robot_mode = MODE_ORDER[here + 1]
        if self.robot_mode == self._target:
            self._target = None

    def _head_for(self, mode):
        if self.robot_mode != mode:
            self._target = mode
            self._timer = 0.0

    def _end_program(self):
        self.external_control_running = False
        self.program_state = STOPPED

    # -- safety -------------------------------------------------------------------

    def protective_stop(self, reason):
        """The robot stopped itself (the joints said why): safety mode PROTECTIVE_STOP, the program paused."""
        if self.safety_mode == PROTECTIVE_STOP:
            return
        self.safety_mode = PROTECTIVE_STOP
        self._stopped_for = 0.0
        if self.program_state == PLAYING:
            self.program_state = PAUSED
        self.add_log('Protective stop: %s' % reason)

    def pause_program(self, reason):
        """The controller paused the running program itself (an RTDE watchdog): in the robot's log."""
        self.add_log(reason)
        if self.program_state == PLAYING:
            self.program_state = PAUSED

    # -- what ROS-side services do directly -----------------------------------

    def set_speed_slider(self, fraction):
        """ur_msgs/SetSpeedSliderFraction: (success, message); 0..1 only."""
        if not 0.0 <= fraction <= 1.0:  # also false for NaN
            return False, 'speed_slider_fraction %r must be within [0, 1]' % fraction
        self.speed_slider = float(fraction)
        return True, ''

    def set_io(self, fun, pin, state):
        """ur_msgs/SetIO: (success, message)."""
        if fun == 1:  # FUN_SET_DIGITAL_OUT: the driver sends the state as a bool, any non-zero is on
            if not 0 <= pin < DIGITAL_PINS:
                return False, 'pin %d: digital outputs are 0-17 (8-15 configurable, 16-17 tool)' % pin
            self.digital_out[pin] = state != 0.0
            return True, ''
        if fun == 3:  # FUN_SET_ANALOG_OUT
            if not 0 <= pin < ANALOG_OUTPUTS:
                return False, 'pin %d: analog outputs are 0 and 1' % pin
            if not 0.0 <= state <= 1.0:
                return False, 'state %r: analog outputs take a fraction 0..1 of their range' % state
            self.analog_out[pin] = float(state)
            return True, ''
        if fun == 4:  # FUN_SET_TOOL_VOLTAGE
            if state not in TOOL_VOLTAGES:
                return False, 'state %r: the tool voltage is 0, 12 or 24' % state
            self.tool_voltage = int(state)
            return True, ''
        # FUN_SET_FLAG (2) too: ur_robot_driver does not implement it.
        return False, 'Cannot execute function %d. This is not (yet) supported: use FUN_SET_DIGITAL_OUT (1), ' \
                      'FUN_SET_ANALOG_OUT (3) or FUN_SET_TOOL_VOLTAGE (4)' % fun

    def set_payload(self, mass, center_of_gravity):
        if not mass >= 0.0 or not all(abs(c) < 10.0 for c in center_of_gravity):
            return False, 'mass %r kg must be >= 0 and the centre of gravity finite' % mass
        self.payload = (float(mass), tuple(center_of_gravity))
        return True, ''

    def resend_robot_program(self):
        """The driver sends its URScript again: the External Control program runs.

        The real driver offers this in headless mode only; the simulated
        controller, which has no teach pendant to play external_control.urp
        from, takes it in either mode (the node warns without headless mode).
        """
        if self.robot_mode != RUNNING:
            return False, 'The robot is %s: it must be RUNNING (set_mode) to run the program' % self.robot_mode
        self.external_control_running = True
        self.program_state = PLAYING
        return True, 'Successfully resent robot program'

    def hand_back_control(self):
        # The driver answers success either way: there is nothing to hand back.
        if not self.program_running:
            return True, 'No control active. Nothing to do.'
        self._end_program()
        return True, 'Deactivated control'

    def program_failed(self, text):
        """The loaded program could not start (the External Control URCap got no script): its popup shows
        `text`, in the log too, and the program stops."""
        self.popup = text
        self.add_log(text)
        self._end_program()

    def script_started(self, secondary):
        """A URScript program arrived: a primary one replaces the running program and plays."""
        if not secondary:
            self._end_program()
            self.program_state = PLAYING

    def script_finished(self):
        """A primary script program ran to its end (the External Control program does not end so)."""
        if not self.external_control_running:
            self.program_state = STOPPED

    # -- the dashboard server ----------------------------------------------------

    def dashboard(self, command):
        """The dashboard server's answer to one command line.

        The table (config/ur_dashboard.yaml) says which commands this software answers and their fixed
        replies; a command's method here (_dashboard_ and its words) does what it does to the robot and
        answers, or returns None for the table's reply.
        """
        command = command.strip()
        key, argument = self.dashboard_commands.match(command)
        if key is None or not self.dashboard_commands.answered(key, self.software):
            return "could not understand: '%s'" % command
        act = getattr(self, '_dashboard_' + key.replace(' ', '_'), None)
        answer = act(argument) if act is not None else None
        if answer is _NOT_UNDERSTOOD:
            return "could not understand: '%s'" % command
        return self.dashboard_commands.reply(key) if answer is None else answer

    def _named(self, argument, names):
        """`argument` as one of `names` (in any case), or _NOT_UNDERSTOOD."""
        return argument.upper() if argument.upper() in names else _NOT_UNDERSTOOD

    def _dashboard_power_on(self, argument):
        if self.robot_mode == POWER_OFF:
            self._head_for(IDLE)

    def _dashboard_power_off(self, argument):
        self.power_off_quietly()

    def _dashboard_brake_release(self, argument):
        self._head_for(RUNNING)

    def _dashboard_play(self, argument):
        if self.safety_mode != SAFETY_NORMAL:
            return 'Failed to execute: play'
        if self.robot_mode == RUNNING and self.program_state == PAUSED:
            self.program_state = PLAYING  # resumes the paused program, e.g. headless mode's script
            return 'Starting program'
        if self.robot_mode != RUNNING or self.loaded_program is None:
            return 'Failed to execute: play'
        self.program_state = PLAYING
        self.external_control_running = self.loaded_program == EXTERNAL_CONTROL
        return 'Starting program'

    def _dashboard_stop(self, argument):
        if self.program_state == STOPPED:
            return 'Failed to execute: stop'
        self._end_program()
        return 'Stopped'

    def _dashboard_pause(self, argument):
        if self.program_state != PLAYING:
            return 'Failed to execute: pause'
        self.program_state = PAUSED
        return 'Pausing program'

    def _dashboard_unlock_protective_stop(self, argument):
        if self.safety_mode == PROTECTIVE_STOP:
            if self._stopped_for < UNLOCK_DELAY:
                return UNLOCK_TOO_EARLY
            self.safety_mode = SAFETY_NORMAL

    def _dashboard_restart_safety(self, argument):
        self.safety_mode = SAFETY_NORMAL
        self._end_program()
        self.robot_mode = POWER_OFF

    def _dashboard_close_popup(self, argument):
        self.popup = None

    def _dashboard_shutdown(self, argument):
        self.power_off_quietly()

    def _dashboard_robotmode(self, argument):
        return 'Robotmode: %s' % self.robot_mode

    def _dashboard_safetymode(self, argument):
        return 'Safetymode: %s' % self.safety_mode

    def _dashboard_safetystatus(self, argument):  # the safety mode under its newer name
        return 'Safetystatus: %s' % self.safety_mode

    def _dashboard_running(self, argument):
        return 'Program running: %s' % ('true' if self.program_state == PLAYING else 'false')

    def _dashboard_programstate(self, argument):
        return '%s %s' % (self.program_state, self.loaded_program or '<unnamed>')

    def _dashboard_get_loaded_program(self, argument):
        return 'Loaded program: %s' % self.loaded_program if self.loaded_program else 'No program loaded'

    def _dashboard_isprogramsaved(self, argument):
        return 'true %s' % (self.loaded_program or '<unnamed>')

    def _dashboard_is_in_remote_control(self, argument):
        return 'true'  # remote control is always on in the simulation

    def _dashboard_get_serial_number(self, argument):
        return self.software.serial_number

    def _dashboard_get_robot_model(self, argument):
        return self.software.model_name

    def _dashboard_polyscopeversion(self, argument):
        return 'URSoftware %s' % self.software.version_text

    def _dashboard_version(self, argument):
        return self.software.version_text

    def _dashboard_generate_flight_report(self, argument):
        if argument.lower() not in self.dashboard_commands.flight_report_types:
            return _NOT_UNDERSTOOD
        self.flight_reports += 1
        return 'Flight Report generated with id: %d' % self.flight_reports

    def _dashboard_generate_support_file(self, argument):
        if not argument:
            return _NOT_UNDERSTOOD
        # Named on the robot's clock (UTC here); nothing is written: the simulation has no robot disk.
        return 'Completed successfully: ur_%s_%s.zip' % (self.software.serial_number,
                                                         time.strftime('%Y-%m-%d_%H-%M-%S', time.gmtime()))

    def _dashboard_load_installation(self, argument):
        return 'Loading installation: %s' % argument if argument else 'File not found: '

    def _dashboard_load(self, argument):
        if argument not in self.programs and argument.split('/')[-1] not in self.programs:
            return 'File not found: %s' % argument
        self._end_program()
        self.loaded_program = argument.split('/')[-1]
        return 'Loading program: %s' % argument

    def _dashboard_addtolog(self, argument):
        if not argument:
            return 'No log message to add'
        self.add_log(argument)
        return 'Added log message'

    def _dashboard_popup(self, argument):
        self.popup = argument

    def _dashboard_setuserrole(self, argument):
        role = self._named(argument, self.dashboard_commands.user_roles)
        if role is _NOT_UNDERSTOOD:
            return role
        self.user_role = role
        return 'Setting user role: %s' % argument

    def _dashboard_getuserrole(self, argument):
        return self.user_role

    def _dashboard_set_operational_mode(self, argument):
        mode = self._named(argument, self.dashboard_commands.operational_modes)
        if mode is _NOT_UNDERSTOOD:
            return mode
        self.operational_mode = mode
        return "Operational mode '%s' is set" % argument

    def _dashboard_clear_operational_mode(self, argument):
        self.operational_mode = None

    def _dashboard_get_operational_mode(self, argument):
        return self.operational_mode or 'NONE'  # NONE: no operational mode password, as in URSim

    def power_off_quietly(self):
        self._end_program()
        self._target = None
        self.robot_mode = POWER_OFF


def plan_set_mode(robot_mode, target, stop_program, safety_mode=SAFETY_NORMAL):
    """The dashboard commands robot_state_helper sends to reach `target`, each with the mode it then waits for.

    Returns a list of (command, robot mode to wait for or None); raises
    ValueError for a mode that cannot be selected. As ur_robot_driver's
    robot_state_helper: nothing to do (not even stopping the program) when
    the robot is in the target mode without a safety stop; a lower mode goes
    through power off; a protective stop is unlocked first on the way up.
    """
    if target not in SELECTABLE_MODES:
        raise ValueError('Requested target mode %s which cannot be explicitly selected: use POWER_OFF, '
                         'IDLE or RUNNING' % target)
    steps = []
    if robot_mode == target and safety_mode == SAFETY_NORMAL:
        return steps
    if stop_program:
        steps.append(('stop', None))
    if MODE_ORDER.index(target) < MODE_ORDER.index(robot_mode):
        steps.append(('power off', POWER_OFF))
        robot_mode = POWER_OFF
    elif safety_mode == PROTECTIVE_STOP:
        steps.append(('unlock protective stop', None))
    if target == IDLE and robot_mode != IDLE:
        steps.append(('power on', IDLE))
    elif target == RUNNING and robot_mode != RUNNING:
        if robot_mode != IDLE:
            steps.append(('power on', IDLE))
        steps.append(('brake release', RUNNING))
    return steps
