"""What URScript programs call on the simulated robot: motion, force mode, state, set-up and IO; no ROS.

The language (parsing, variables, control flow, threads) is the urscript
package's; it hands every call of a robot function to `ScriptRobot.call`.
This module is the robot's side, as the URScript manual defines each
function (its defaults and units), for the generation the simulated robot
reports (ControllerSoftware): `served()` names the functions it offers, so
that a program calling one the robot lacks, or one the manual has and the
simulation does not offer, is refused whole when it compiles.

Motions come from tool_motion (movej, movel, movep, servoj, speedj, speedl,
stopj, stopl); a call that moves returns an urscript.Blocking that frees the
program when the motion returns (at its end, or on entering its blend
radius). force_mode (force_mode.py) displaces whatever the program commands
along its compliant axes, driven by the robot's own TCP wrench
(tcp_wrench.py, the flange's reading on physics; zero without physics, where
the compliant axes then run at their speed limits as in URSim).

The installation header PolyScope writes first in every program is served:
set_tcp, set_payload and set_tool_voltage change the robot; set_gravity
takes the upright base's gravity only; the settings the simulated robot has
no state for (INSTALLATION_SETTINGS) are checked and change nothing. The
tool flange's settings are the e-Series' only, as on the robot.
get_steptime() is the generation's control period (STEP_TIME).

Every cycle the arm's core calls `command(dt)` for the joint positions to
command. Errors a call can meet (an unreachable pose, a bad argument) raise
urscript.RuntimeFault, which stops the program as the robot's runtime
exception does.
"""

import math
import struct

import numpy as np

from ...urscript import Blocking, Pose, RuntimeFault
from ...urscript.values import to_str, type_name
from . import cartesian
from . import force_mode as fm
from . import robot_state as rs
from . import script_sockets as ss
from .script_rpc import ScriptRpc
from .script_modbus import DIGITAL_OUTPUT, REGISTER_OUTPUT, ScriptModbus
from . import tool_motion as tm
from .arm_kinematics import rigid_inverse
from .registers import BOOLEAN, FLOAT, INTEGER, RegisterError
from .software import CB3, E_SERIES

# IO numbering of ur_msgs/IOStates (and of the core's set_io): 0-7 standard, 8-15 configurable, 16-17 tool.
CONFIGURABLE_OFFSET, TOOL_OFFSET = 8, 16
# is_steady(): every joint slower than this (rad/s) and no motion running.
STEADY_SPEED = 1e-3
# At a program's end a speed motion still running is stopped with this deceleration (rad/s^2), as
# the robot decelerates the arm when its program stops.
END_OF_PROGRAM_DECELERATION = 4.0
A = object()  # stands for "the value of argument a" (stopl's and speedl's aRot default)
# get_steptime(): the controller's time step (s), by generation: CB3 125 Hz, e-Series 500 Hz.
STEP_TIME = {CB3: 0.008, E_SERIES: 0.002}
# set_gravity(d): the simulated arm stands on its base, and its payload compensation (tcp_wrench.py)
# takes gravity along the base's -z; a d off the base's +z by more than this (rad) is refused.
GRAVITY_ALONG_Z = 1e-3
# tool_contact(direction): a force on the TCP against the direction (N) from which there is contact. The
# robot detects contact from its joints' currents and UR gives no figure; the twin measures its TCP's wrench
# (tcp_wrench.py; zero without physics), and 5 N stands clear of its noise at rest.
TOOL_CONTACT_FORCE = 5.0
# How near (m, rad) the joints force mode commands put the TCP to its pose. The inverse kinematics'
# default (10 um) is a dead band the admittance's small steps in a press fall into, and then leap out
# of: against a table that is a force jumping by 1 to 2 N. Under 1 nm it is under a thousandth of a N.
FORCE_MODE_REACH, FORCE_MODE_REACH_ITERATIONS = 1e-9, 10
# rtde_set_watchdog's actions, as the manual names them.
WATCHDOG_IGNORE, WATCHDOG_PAUSE, WATCHDOG_STOP = 'ignore', 'pause', 'stop'
# The external F/T sensor's switches (enable_external_ft_sensor, ft_rtde_input_enable): the manual's parameters.
EXTERNAL_FT = ('enable', 'sensor_mass', 'sensor_measuring_offset', 'sensor_cog')
EXTERNAL_FT_DEFAULTS = {'sensor_mass': 0.0, 'sensor_measuring_offset': [0.0, 0.0, 0.0], 'sensor_cog': [0.0, 0.0, 0.0]}
# servoc's defaults (the manual's): tool acceleration (m/s^2), speed (m/s), blend radius (m).
SERVOC_A, SERVOC_V = 1.2, 0.25
# The general purpose registers' functions (registers.py): name -> (access, direction, kind).
REGISTER_FUNCTIONS = {'%s_%s_%s_register' % (access, direction, kind): (access, direction, kind)
                      for access, direction in (('read', 'input'), ('read', 'output'), ('write', 'output'))
                      for kind in (BOOLEAN, INTEGER, FLOAT)}


class OneOf(object):
    """The values a parameter takes, as `value in OneOf(...)`: bools and numbers apart, as URScript keeps them."""

    def __init__(self, *values):
        self.values = values

    def __contains__(self, value):
        return any(value == v and isinstance(value, bool) == isinstance(v, bool) for v in self.values)

    def __repr__(self):
        return ' or '.join(to_str(v) for v in self.values)


class AtLeast(object):
    """A number not below `minimum`, as `value in AtLeast(m)`."""

    def __init__(self, minimum):
        self.minimum = minimum

    def __contains__(self, value):
        return isinstance(value, (int, float)) and not isinstance(value, bool) and value >= self.minimum

    def __repr__(self):
        return 'a number >= %g' % self.minimum


# Installation settings a program's header sets (PolyScope writes them first in every program) that
# the simulated robot keeps no state for: nothing reads an analog domain, a tool's RS-485 or output
# mode, the input actions or how hard a safety stop brakes. A call is checked against the manual's
# values of each parameter, then changes nothing. The e-Series' tool flange alone has the last three.
INSTALLATION_SETTINGS = {
    # 0: hard, 1: soft.
    'set_safety_mode_transition_hardness': {'type': OneOf(0, 1)},
    # Domains: 0 current (4-20 mA), 1 voltage (0-10 V).
    'set_analog_outputdomain': {'port': OneOf(0, 1), 'domain': OneOf(0, 1)},
    'set_standard_analog_input_domain': {'port': OneOf(0, 1), 'domain': OneOf(0, 1)},
    'set_tool_analog_input_domain': {'port': OneOf(0, 1), 'domain': OneOf(0, 1)},
    'set_input_actions_to_default': {},
}
E_SERIES_INSTALLATION_SETTINGS = {
    # Parity: 0 none, 1 odd, 2 even; idle times in characters.
    'set_tool_communication': {'enabled': OneOf(False, True),
                               'baud_rate': OneOf(9600, 19200, 38400, 57600, 115200, 1000000, 2000000, 5000000),
                               'parity': OneOf(0, 1, 2), 'stop_bits': OneOf(1, 2), 'rx_idle_chars': AtLeast(1.0),
                               'tx_idle_chars': AtLeast(0.0)},
    # 0: digital outputs, 1: dual pin power.
    'set_tool_output_mode': {'mode': OneOf(0, 1)},
    # 1: sinking (NPN), 2: sourcing (PNP), 3: push/pull.
    'set_tool_digital_output_mode': {'n': OneOf(0, 1), 'mode': OneOf(1, 2, 3)},
}


def _number(what, value, kind):
    """`value` as `kind` (int or float) for function `what`; the robot's type error for what is not a number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise RuntimeFault('Type error: %s takes a number, not %s' % (what, type_name(value)))
    if not math.isfinite(value):
        raise RuntimeFault('%s takes a finite number, not %r' % (what, value))
    return kind(value)


def _integer(what, value):
    """`value` as an int for function `what`; the robot's type error for what is not a whole number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise RuntimeFault('Type error: %s takes an int, not %s' % (what, type_name(value)))
    if not (math.isfinite(value) and value == int(value)):
        raise RuntimeFault('Type error: %s takes an int, not %s' % (what, to_str(value)))
    return int(value)


class Signature(object):
    """A function's parameter names and defaults (a parameter without a default is required)."""

    def __init__(self, physical_time, *params, **defaults):
        self.physical_time = physical_time
        self.params = params
        self.defaults = defaults

    def bind(self, name, args, kwargs):
        if len(args) > len(self.params):
            raise RuntimeFault('%s takes at most %d arguments, %d given' % (name, len(self.params), len(args)))
        bound = dict(zip(self.params, args))
        for key, value in kwargs.items():
            if key not in self.params:
                raise RuntimeFault('%s has no argument named %s' % (name, key))
            bound[key] = value
        for param in self.params:
            if param not in bound:
                if param not in self.defaults:
                    raise RuntimeFault('%s: argument %s is missing' % (name, param))
                bound[param] = self.defaults[param]
        return bound


def _installation_settings(e_series):
    """{name: {parameter: its values}} of the header's settings this generation's robot takes."""
    return dict(INSTALLATION_SETTINGS, **(E_SERIES_INSTALLATION_SETTINGS if e_series else {}))


def _signatures(e_series, version):
    """{name: Signature} of the functions the simulated robot of this generation offers."""
    move, now = True, False
    functions = {
        'movej': Signature(move, 'q', 'a', 'v', 't', 'r', a=tm.MOVEJ_A, v=tm.MOVEJ_V, t=0.0, r=0.0),
        'movel': Signature(move, 'pose', 'a', 'v', 't', 'r', a=tm.MOVEL_A, v=tm.MOVEL_V, t=0.0, r=0.0),
        'movep': Signature(move, 'pose', 'a', 'v', 'r', a=tm.MOVEP_A, v=tm.MOVEP_V, r=0.0),
        'servoj': Signature(move, 'q', 'a', 'v', 't', 'lookahead_time', 'gain', a=0.0, v=0.0, t=tm.SERVOJ_T,
                            lookahead_time=tm.SERVOJ_LOOKAHEAD_TIME, gain=tm.SERVOJ_GAIN),
        'speedj': Signature(move, 'qd', 'a', 't', t=0.0),
        'speedl': Signature(move, 'xd', 'a', 't', 'aRot', t=0.0, aRot=A),
        'stopj': Signature(move, 'a'),
        'stopl': Signature(move, 'a', 'aRot', aRot=A),
        'force_mode': Signature(now, 'task_frame', 'selection_vector', 'wrench', 'type', 'limits'),
        'end_force_mode': Signature(now),
        'force_mode_set_damping': Signature(now, 'damping'),
        'get_actual_joint_positions': Signature(now),
        'get_target_joint_positions': Signature(now),
        'get_actual_joint_speeds': Signature(now),
        'get_target_joint_speeds': Signature(now),
        'get_actual_tcp_pose': Signature(now),
        'get_target_tcp_pose': Signature(now),
        'get_actual_tool_flange_pose': Signature(now),
        'get_actual_tcp_speed': Signature(now),
        'get_target_tcp_speed': Signature(now),
        'get_tcp_force': Signature(now),
        'get_tcp_offset': Signature(now),
        'get_inverse_kin': Signature(now, 'x', 'qnear', 'maxPositionError', 'maxOrientationError', 'tcp',
                                     qnear=None, maxPositionError=1e-10, maxOrientationError=1e-10, tcp=None),
        'get_forward_kin': Signature(now, 'q', 'tcp', q=None, tcp=None),
        'is_steady': Signature(now),
        'tool_pose': Signature(now),
        'set_tcp': Signature(now, 'pose'),
        'set_payload': Signature(now, 'm', 'cog', cog=None),
        'set_payload_mass': Signature(now, 'm'),
        'set_payload_cog': Signature(now, 'CoG'),
        'set_standard_digital_out': Signature(now, 'n', 'b'),
        'set_configurable_digital_out': Signature(now, 'n', 'b'),
        'set_tool_digital_out': Signature(now, 'n', 'b'),
        'set_digital_out': Signature(now, 'n', 'b'),
        'set_standard_analog_out': Signature(now, 'n', 'f'),
        'set_analog_out': Signature(now, 'n', 'f'),
        'set_tool_voltage': Signature(now, 'voltage'),
        'get_standard_digital_in': Signature(now, 'n'),
        'get_standard_digital_out': Signature(now, 'n'),
        'get_configurable_digital_in': Signature(now, 'n'),
        'get_configurable_digital_out': Signature(now, 'n'),
        'get_tool_digital_in': Signature(now, 'n'),
        'get_tool_digital_out': Signature(now, 'n'),
        'get_digital_in': Signature(now, 'n'),
        'get_digital_out': Signature(now, 'n'),
        'get_standard_analog_in': Signature(now, 'n'),
        'get_analog_in': Signature(now, 'n'),
        'textmsg': Signature(now, 's1', 's2', s2=''),
        'popup': Signature(now, 's', 'title', 'warning', 'error', 'blocking', title='Popup', warning=False,
                           error=False, blocking=False),
        'get_steptime': Signature(now),
        'set_gravity': Signature(now, 'd'),
        'socket_open': Signature(move, 'address', 'port', 'socket_name', socket_name=ss.DEFAULT_SOCKET),
        'socket_close': Signature(now, 'socket_name', socket_name=ss.DEFAULT_SOCKET),
        'socket_send_string': Signature(now, 'str', 'socket_name', socket_name=ss.DEFAULT_SOCKET),
        'socket_send_line': Signature(now, 'str', 'socket_name', socket_name=ss.DEFAULT_SOCKET),
        'socket_send_byte': Signature(now, 'value', 'socket_name', socket_name=ss.DEFAULT_SOCKET),
        'socket_send_int': Signature(now, 'value', 'socket_name', socket_name=ss.DEFAULT_SOCKET),
        'socket_set_var': Signature(now, 'name', 'value', 'socket_name', socket_name=ss.DEFAULT_SOCKET),
        'socket_get_var': Signature(move, 'name', 'socket_name', socket_name=ss.DEFAULT_SOCKET),
        'socket_read_binary_integer': Signature(move, 'number', 'socket_name', 'timeout', socket_name=ss.DEFAULT_SOCKET,
                                                timeout=ss.READ_TIMEOUT),
        'socket_read_byte_list': Signature(move, 'number', 'socket_name', 'timeout', socket_name=ss.DEFAULT_SOCKET,
                                           timeout=ss.READ_TIMEOUT),
        'socket_read_ascii_float': Signature(move, 'number', 'socket_name', 'timeout', socket_name=ss.DEFAULT_SOCKET,
                                             timeout=ss.READ_TIMEOUT),
        'socket_read_line': Signature(move, 'socket_name', 'timeout', socket_name=ss.DEFAULT_SOCKET,
                                      timeout=ss.READ_TIMEOUT),
        'socket_read_string': Signature(move, 'socket_name', 'prefix', 'suffix', 'interpret_escape', 'timeout',
                                        socket_name=ss.DEFAULT_SOCKET, prefix='', suffix='', interpret_escape=False,
                                        timeout=ss.READ_TIMEOUT),
        'servoc': Signature(move, 'pose', 'a', 'v', 'r', a=SERVOC_A, v=SERVOC_V, r=0.0),
        'tool_contact': Signature(now, 'direction'),
        'get_actual_joint_positions_history': Signature(now, 'steps', steps=0),
        'get_target_waypoint': Signature(now),
        'get_joint_torques': Signature(now),
        'get_target_payload': Signature(now),
        'get_target_payload_cog': Signature(now),
        'is_within_safety_limits': Signature(now, 'pose'),
        'protective_stop': Signature(move),
        'rtde_set_watchdog': Signature(now, 'variable_name', 'min_frequency', 'action', action=WATCHDOG_PAUSE),
        'enable_external_ft_sensor': Signature(now, *EXTERNAL_FT, **EXTERNAL_FT_DEFAULTS),
        'zero_ftsensor': Signature(now),
        'modbus_add_signal': Signature(now, 'IP', 'slave_number', 'signal_address', 'signal_type', 'signal_name',
                                       'sequential_mode', sequential_mode=False),
        'modbus_delete_signal': Signature(now, 'signal_name'),
        'modbus_send_custom_command': Signature(now, 'IP', 'slave_number', 'function_code', 'data'),
        'rpc_factory': Signature(now, 'type', 'url'),
        'modbus_set_signal_update_frequency': Signature(now, 'signal_name', 'update_frequency'),
        # With an update frequency of 0 a read waits for the unit's answer.
        'modbus_get_signal_status': Signature(move, 'signal_name', 'is_secondary_program',
                                              is_secondary_program=False),
        'modbus_set_output_register': Signature(now, 'signal_name', 'register_value', 'is_secondary_program',
                                                is_secondary_program=False),
        'modbus_set_output_signal': Signature(now, 'signal_name', 'digital_value', 'is_secondary_program',
                                              is_secondary_program=False),
        'freedrive_mode': Signature(now),
        'end_freedrive_mode': Signature(now),
        'teach_mode': Signature(now),
        'end_teach_mode': Signature(now),
    }
    for name, values in _installation_settings(e_series).items():
        functions[name] = Signature(now, *values)
    for name, (access, _, _) in REGISTER_FUNCTIONS.items():
        functions[name] = Signature(now, 'address', 'value') if access == 'write' else Signature(now, 'address')
    if e_series:
        # The e-Series' own: force mode's gain (a CB3 zeroes its TCP wrench too: ur_rtde's script for
        # CB3 calls zero_ftsensor, and ur_rtde strips only what a CB3 lacks).
        functions['force_mode_set_gain_scaling'] = Signature(now, 'scaling')
        functions['ft_rtde_input_enable'] = Signature(now, *EXTERNAL_FT, **EXTERNAL_FT_DEFAULTS)
        if tuple(version[:2]) >= (5, 10):
            functions['set_target_payload'] = Signature(now, 'mass', 'center_of_gravity', 'inertia',
                                                        'transition_time', inertia=None, transition_time=0.0)
    return functions


def _floats(value, length, what):
    try:
        values = [float(v) for v in value]
    except (TypeError, ValueError):
        raise RuntimeFault('%s must be a list of %d numbers' % (what, length)) from None
    if len(values) != length or not np.all(np.isfinite(values)):
        raise RuntimeFault('%s must be a list of %d finite numbers' % (what, length))
    return np.array(values)


def _matrix(pose, what):
    if not isinstance(pose, Pose):
        raise RuntimeFault('%s must be a pose p[x, y, z, rx, ry, rz]' % what)
    return cartesian.pose_from_ur_pose(_floats(pose, 6, what))


def _pose(matrix):
    return Pose(tm.ur_pose_of(matrix))


def _text(value, what):
    if not isinstance(value, str):
        raise RuntimeFault('%s must be a string, not %s' % (what, to_str(value)))
    return value


class ScriptRobot(object):
    """The robot's functions for programs, over the arm's core (core.ArmCore) it belongs to."""

    def __init__(self, core):
        self.core = core
        software = core.software
        self.signatures = _signatures(software.e_series, software.version)
        self.settings = _installation_settings(software.e_series)
        self.motion = None            # the tool_motion in progress
        self.force = None             # force_mode.ForceMode while force mode is on
        self.force_damping, self.force_gain = fm.DEFAULT_DAMPING, fm.DEFAULT_GAIN_SCALING
        self.force_offset = np.eye(4)  # force mode's displacement of the TCP (base axes, about the TCP)
        self.commanded = None         # the joints commanded last cycle
        self.commanded_speed = np.zeros(6)
        # The program's own joint speed: the commanded speed without force mode's displacement, which a
        # new motion or a stop starts from (the displacement stays apart).
        self.planned_speed = np.zeros(6)
        self.sockets = ss.ScriptSockets(lambda: core.uptime, core.socket_hosts)
        self.modbus = ScriptModbus(lambda function, ip: self.sockets.check_reach(ip, function),
                                   core.say_warning, core.modbus_port)
        self.rpc = ScriptRpc(self.sockets.check_reach)
        self.watchdogs = {}           # rtde_set_watchdog's: {variable: (period s, action, set at uptime)}

    def served(self):
        """{name: whether a call takes physical time}, for urscript.compile_script."""
        return {name: signature.physical_time for name, signature in self.signatures.items()}

    # -- the control cycle -------------------------------------------------------------------------

    def start(self):
        """A program starts: it commands from where the joints are."""
        self.motion, self.force = None, None
        self.watchdogs = {}
        self.force_offset = np.eye(4)
        self.commanded = self.core.actual_state()[0]
        self.planned = self.commanded.copy()
        self.commanded_speed = np.zeros(6)
        self.planned_speed = np.zeros(6)

    @property
    def moving(self):
        return self.motion is not None and not self.motion.done

    def finish(self):
        """The program ended: force mode ends, a speed motion still running decelerates, and its sockets
        close."""
        self._end_force_mode()
        self.sockets.close_all()
        self.watchdogs = {}  # the manual: all watchdogs are removed on program stop
        if self.moving and isinstance(self.motion, (tm.ToolSpeed, tm.JointSpeed)) and \
                not isinstance(self.motion, (tm.ToolStop, tm.JointStop)):
            self.motion = tm.JointStop(self.core.arm, self.planned, self.planned_speed,
                                       END_OF_PROGRAM_DECELERATION, previous=self.motion)

    def command(self, dt):
        """The joint positions to command for the end of this cycle of `dt` s (RuntimeFault if the arm cannot)."""
        arm = self.core.arm
        previous = self.planned
        if self.motion is not None:
            try:
                self.planned = self.motion.step(dt)
            except tm.MotionError as exc:
                self.motion = None
                raise RuntimeFault(str(exc)) from None
        if dt > 0:
            self.planned_speed = (self.planned - previous) / dt
        target = self.planned
        if self.force is not None or not np.allclose(self.force_offset, np.eye(4)):
            tcp = self.core.tcp
            planned = tm.tcp_pose(arm, tcp, self.planned)
            motion = self.core.motion
            # Joint servos that give (force_mode.py): the admittance runs against their damping, and what it
            # asks beyond where its motion takes the TCP pulls along the compliant axes only.
            giving = self.force is not None and motion.stiffness is not None
            if giving:
                actual = self.core.actual_state()[0]
                jacobian = arm.jacobian(actual, tcp)
            if self.force is not None:
                external = self.core.tcp_force()[0]
                damping = fm.servos_at_tcp(jacobian, motion.servo_damping) if giving else None
                linear, angular = self.force.step(dt, self.force_offset[:3, 3] + planned[:3, 3], external, damping)
                self.force_offset = fm.displaced(self.force_offset, linear, angular)
            pose = self._displaced_pose(planned)
            if not giving:
                target = self._reach(pose)
            else:
                frame = self.force.frame
                travel = self.force.velocity * dt
                going = fm.displaced(tm.tcp_pose(arm, tcp, actual), frame.dot(travel[:3]), frame.dot(travel[3:]))
                ahead = fm.lead(frame, self.force.selection, pose, going)
                shift = fm.uncoupled(jacobian, motion.stiffness, frame, self.force.selection, ahead)
                target = self._reach(fm.displaced(pose, *shift))
        if dt > 0:
            self.commanded_speed = (target - self.commanded) / dt
        self.commanded = np.array(target, dtype=float)
        return self.commanded

    def expired_watchdog(self):
        """(action, text) of the first RTDE watchdog whose variable was not written within its period, once
        (it is removed), or None."""
        now = self.core.uptime
        for name, (period, action, since) in sorted(self.watchdogs.items()):
            if now - max(since, self.core.rtde_input_times.get(name, since)) > period:
                del self.watchdogs[name]
                if action != WATCHDOG_IGNORE:
                    return action, ('RTDE input watchdog: %s was not written for %g s (min_frequency %g Hz)'
                                    % (name, period, 1.0 / period))
        return None

    def _displaced_pose(self, planned=None):
        """The TCP's pose the program plans (`planned`, where the caller has it), displaced by force mode
        (4x4, base axes)."""
        pose = tm.tcp_pose(self.core.arm, self.core.tcp, self.planned) if planned is None else planned.copy()
        pose[:3, 3] += self.force_offset[:3, 3]
        pose[:3, :3] = self.force_offset[:3, :3].dot(pose[:3, :3])
        return pose

    def _reach(self, pose):
        """Joint positions putting the TCP at `pose`, from the last command."""
        flange = pose.dot(rigid_inverse(self.core.tcp))
        target = self.core.arm.inverse(flange, self.commanded, FORCE_MODE_REACH, FORCE_MODE_REACH_ITERATIONS)
        if target is None:
            # Near a singularity the last nanometres do not converge: there the default reach.
            target = self.core.arm.inverse(flange, self.commanded)
        if target is None:
            raise RuntimeFault('force_mode: the pose it asks for is out of the arm\'s reach')
        return target

    # -- calls -------------------------------------------------------------------------------------

    def call(self, name, args, kwargs):
        signature = self.signatures.get(name)
        if signature is None:
            raise RuntimeFault('%s is not a function of the simulated robot' % name)
        bound = signature.bind(name, args, kwargs)
        if name in self.settings:
            return self._installation_setting(name, bound)
        if name in REGISTER_FUNCTIONS:
            return self._register(name, **bound)
        return getattr(self, '_' + name)(**bound)

    def call_method(self, handle, name, args):
        """A method of a handle a function gave the program: rpc_factory's remote procedures."""
        return self.rpc.call(handle, name, args)

    def _rpc_factory(self, type, url):
        return self.rpc.factory(type, url)

    def _start_motion(self, motion):
        self.motion = motion
        return Blocking(lambda: motion.returned or self.motion is not motion)

    def _previous(self):
        return self.motion if self.moving else None

    def _q_start(self):
        """Where a new motion starts: the program's own joints (force mode's displacement stays apart)."""
        if self.force is None and not self.moving:
            # Force mode ended where it brought the arm: from there the program goes on.
            self.force_offset = np.eye(4)
            self.planned = self.commanded.copy()
            if self.motion is not None and not isinstance(self.motion, tm.Servo):
                # A move or a stop ended at rest: its last cycle's mean speed is not the arm's speed (a
                # speedl after a movej would start with it, and turn the tool it was told not to turn).
                return self.planned, np.zeros(6)
        return self.planned, self.planned_speed

    def _motion(self, build):
        try:
            return self._start_motion(build())
        except tm.MotionError as exc:
            raise RuntimeFault(str(exc)) from None

    def _joints_or_pose(self, target, what):
        if isinstance(target, Pose):
            flange = _matrix(target, what).dot(rigid_inverse(self.core.tcp))
            solved = self.core.arm.nearest_inverse(flange, self._q_start()[0])
            if solved is None:
                raise RuntimeFault('%s: the pose %s is out of the arm\'s reach' % (what, to_str(target)))
            return solved
        return _floats(target, 6, what)

    def _movej(self, q, a, v, t, r):
        target = self._joints_or_pose(q, 'movej')
        return self._motion(lambda: tm.JointMove(self.core.arm, *self._q_start(), q_target=target, a=a, v=v,
                                                 t=t, r=r, tcp=self.core.tcp, previous=self._previous()))

    def _cartesian_target(self, pose, what):
        if not isinstance(pose, Pose):
            # movel and movep take joint positions too: the pose they give.
            return tm.tcp_pose(self.core.arm, self.core.tcp, _floats(pose, 6, what))
        return _matrix(pose, what)

    def _movel(self, pose, a, v, t, r, what='movel'):
        target = self._cartesian_target(pose, what)
        return self._motion(lambda: tm.LinearMove(self.core.arm, self.core.tcp, *self._q_start(), target_pose=target,
                                                  a=a, v=v, t=t, r=r, previous=self._previous()))

    def _servoc(self, pose, a, v, r):
        # Servo in a circle-blended line in tool space: movel's straight line at tool speed v, blended by r.
        return self._movel(pose, a, v, 0.0, r, what='servoc')

    def _movep(self, pose, a, v, r):
        target = self._cartesian_target(pose, 'movep')
        return self._motion(lambda: tm.ProcessMove(self.core.arm, self.core.tcp, *self._q_start(),
                                                   target_pose=target, a=a, v=v, r=r, previous=self._previous()))

    def _servoj(self, q, a, v, t, lookahead_time, gain):
        target = _floats(q, 6, 'servoj')
        return self._motion(lambda: tm.Servo(self.core.arm, *self._q_start(), q=target, a=a, v=v, t=t,
                                             lookahead_time=lookahead_time, gain=gain, previous=self._previous()))

    def _speedj(self, qd, a, t):
        speeds = _floats(qd, 6, 'speedj')
        return self._motion(lambda: tm.JointSpeed(self.core.arm, *self._q_start(), qd=speeds, a=a, t=t,
                                                  minimum_time=not self.core.software.e_series,
                                                  previous=self._previous()))

    def _speedl(self, xd, a, t, aRot):
        twist = _floats(xd, 6, 'speedl')
        return self._motion(lambda: tm.ToolSpeed(self.core.arm, self.core.tcp, *self._q_start(), xd=twist, a=a, t=t,
                                                 aRot=a if aRot is A else aRot,
                                                 minimum_time=self.core.software.version[:2] < (3, 3),
                                                 previous=self._previous()))

    def _stopj(self, a):
        return self._motion(lambda: tm.JointStop(self.core.arm, *self._q_start(), a=a, previous=self._previous()))

    def _stopl(self, a, aRot):
        return self._motion(lambda: tm.ToolStop(self.core.arm, self.core.tcp, *self._q_start(), a=a,
                                                aRot=a if aRot is A else aRot, previous=self._previous()))

    # force mode

    def _force_mode(self, task_frame, selection_vector, wrench, type, limits):
        frame = _matrix(task_frame, 'force_mode: task_frame')
        try:
            force = fm.ForceMode(frame, selection_vector, wrench, type, limits, self.force_damping, self.force_gain)
        except fm.ForceModeError as exc:
            raise RuntimeFault(str(exc)) from None
        if self.force is not None:
            force.velocity = self.force.velocity
        self.force = force

    def _end_force_mode(self):
        """The arm stays where force mode brought it (the displacement is kept until the next motion).

        On joint servos that give, that is where the TCP is along the compliant axes: the push ends.
        """
        force, self.force = self.force, None
        if force is None or self.core.motion.stiffness is None:
            return
        pose = self._displaced_pose()
        ahead = fm.lead(force.frame, force.selection, pose, tm.tcp_pose(self.core.arm, self.core.tcp,
                                                                        self.core.actual_state()[0]))
        self.force_offset = fm.displaced(self.force_offset, *fm.back(force.frame, ahead))

    def _force_mode_set_damping(self, damping):
        self.force_damping = min(max(float(damping), 0.0), 1.0)

    def _force_mode_set_gain_scaling(self, scaling):
        self.force_gain = min(max(float(scaling), 0.0), 2.0)

    # state

    def _get_actual_joint_positions(self):
        return [float(v) for v in self.core.actual_state()[0]]

    def _get_target_joint_positions(self):
        return [float(v) for v in self.commanded]

    def _get_actual_joint_speeds(self):
        return [float(v) for v in self.core.actual_state()[1]]

    def _get_target_joint_speeds(self):
        return [float(v) for v in self.commanded_speed]

    def _get_actual_tcp_pose(self):
        return _pose(tm.tcp_pose(self.core.arm, self.core.tcp, self.core.actual_state()[0]))

    _tool_pose = _get_actual_tcp_pose

    def _get_target_tcp_pose(self):
        return _pose(tm.tcp_pose(self.core.arm, self.core.tcp, self.commanded))

    def _get_actual_tool_flange_pose(self):
        return _pose(self.core.arm.forward(self.core.actual_state()[0]))

    def _tcp_speed(self, q, qd):
        twist = tm.tcp_jacobian(self.core.arm, self.core.tcp, q).dot(qd)
        return [float(v) for v in twist]

    def _get_actual_tcp_speed(self):
        return self._tcp_speed(*self.core.actual_state())

    def _get_target_tcp_speed(self):
        return self._tcp_speed(self.commanded, self.commanded_speed)

    def _get_tcp_force(self):
        return Pose([float(v) for v in self.core.tcp_force()[0]])

    def _get_tcp_offset(self):
        return _pose(self.core.tcp)

    def _get_inverse_kin(self, x, qnear, maxPositionError, maxOrientationError, tcp):
        offset = self.core.tcp if tcp is None else _matrix(tcp, 'get_inverse_kin: tcp')
        near = self.core.actual_state()[0] if qnear is None else _floats(qnear, 6, 'get_inverse_kin: qnear')
        solved = self.core.arm.nearest_inverse(_matrix(x, 'get_inverse_kin: x').dot(rigid_inverse(offset)), near)
        if solved is None:
            raise RuntimeFault('get_inverse_kin: no solution for the pose %s' % to_str(x))
        return [float(v) for v in solved]

    def _get_forward_kin(self, q, tcp):
        joints = self.core.actual_state()[0] if q is None else _floats(q, 6, 'get_forward_kin: q')
        offset = self.core.tcp if tcp is None else _matrix(tcp, 'get_forward_kin: tcp')
        return _pose(tm.tcp_pose(self.core.arm, offset, joints))

    def _is_steady(self):
        return bool(not self.moving and np.all(np.abs(self.core.actual_state()[1]) < STEADY_SPEED))

    def _get_actual_joint_positions_history(self, steps):
        history = self.core.history
        if isinstance(steps, bool) or not isinstance(steps, int) or not 0 <= steps < len(history):
            raise RuntimeFault('get_actual_joint_positions_history: steps must be an integer from 0 to %d (the '
                               'history the simulated robot keeps), not %s' % (history.maxlen - 1, to_str(steps)))
        return [float(v) for v in history[steps][0]]

    def _get_target_waypoint(self):
        if self.moving and isinstance(self.motion, tm.PathMotion):
            return _pose(self.motion.end_pose)
        return self._get_target_tcp_pose()

    def _get_joint_torques(self):
        # The torques the external wrench at the TCP puts on the joints: what the robot's are beyond those of
        # moving itself (the manual), J^T F.
        jacobian = self.core.arm.jacobian(self.core.actual_state()[0], self.core.tcp)
        return [float(v) for v in jacobian.T.dot(self.core.tcp_force()[0])]

    def _tool_contact(self, direction):
        along = _floats(direction, 6, 'tool_contact: direction')[:3]
        length = float(np.linalg.norm(along))
        if length == 0.0:
            return 0  # no direction of motion: nothing to meet
        against = -along / length
        steps = 0
        for _, wrench in self.core.history:
            if wrench[:3].dot(against) < TOOL_CONTACT_FORCE:
                break
            steps += 1
        return steps

    def _is_within_safety_limits(self, pose):
        arm = self.core.arm
        if isinstance(pose, Pose):
            flange = _matrix(pose, 'is_within_safety_limits').dot(rigid_inverse(self.core.tcp))
            return arm.nearest_inverse(flange, self.core.actual_state()[0]) is not None
        q = _floats(pose, 6, 'is_within_safety_limits')
        return bool(np.all(q >= arm.lower) and np.all(q <= arm.upper))

    def _protective_stop(self):
        # The program waits where it called it, and goes on from there once the stop is unlocked and played.
        robot = self.core.robot
        robot.protective_stop('the program called protective_stop()')
        return Blocking(lambda: robot.safety_mode != rs.PROTECTIVE_STOP)

    def _rtde_set_watchdog(self, variable_name, min_frequency, action):
        name = _text(variable_name, 'rtde_set_watchdog: variable_name')
        inputs = self.core.rtde_inputs
        if inputs is not None and name not in inputs:
            raise RuntimeFault('rtde_set_watchdog: %s is not an RTDE input of this controller' % name)
        if isinstance(min_frequency, bool) or not isinstance(min_frequency, (int, float)) or not min_frequency > 0:
            raise RuntimeFault('rtde_set_watchdog: min_frequency must be a number above 0 Hz, not %s'
                               % to_str(min_frequency))
        if action not in OneOf(WATCHDOG_IGNORE, WATCHDOG_PAUSE, WATCHDOG_STOP):
            raise RuntimeFault('rtde_set_watchdog: action must be "ignore", "pause" or "stop", not %s'
                               % to_str(action))
        self.watchdogs[name] = (1.0 / min_frequency, action, self.core.uptime)

    def _external_ft(self, what, enable, sensor_mass, sensor_measuring_offset, sensor_cog):
        _floats([sensor_mass], 1, '%s: sensor_mass' % what)
        _floats(sensor_measuring_offset, 3, '%s: sensor_measuring_offset' % what)
        _floats(sensor_cog, 3, '%s: sensor_cog' % what)
        if enable is True:
            raise RuntimeFault('%s: the simulated robot measures its own TCP wrench and takes no external F/T '
                               'sensor\'s readings' % what)
        if enable is not False:
            raise RuntimeFault('%s: enable must be True or False, not %s' % (what, to_str(enable)))

    def _enable_external_ft_sensor(self, enable, sensor_mass, sensor_measuring_offset, sensor_cog):
        self._external_ft('enable_external_ft_sensor', enable, sensor_mass, sensor_measuring_offset, sensor_cog)

    def _ft_rtde_input_enable(self, enable, sensor_mass, sensor_measuring_offset, sensor_cog):
        self._external_ft('ft_rtde_input_enable', enable, sensor_mass, sensor_measuring_offset, sensor_cog)

    # set-up

    def _get_target_payload(self):
        return float(self.core.robot.payload[0])

    def _get_target_payload_cog(self):
        return [float(v) for v in self.core.robot.payload[1]]

    def _set_tcp(self, pose):
        self.core.tcp = _matrix(pose, 'set_tcp')

    def _set_payload(self, m, cog):
        centre = self.core.robot.payload[1] if cog is None else tuple(_floats(cog, 3, 'set_payload: cog'))
        self._payload(m, centre)

    def _set_payload_mass(self, m):
        self._payload(m, self.core.robot.payload[1])

    def _set_payload_cog(self, CoG):
        self._payload(self.core.robot.payload[0], tuple(_floats(CoG, 3, 'set_payload_cog')))

    def _set_target_payload(self, mass, center_of_gravity, inertia, transition_time):
        self._payload(mass, tuple(_floats(center_of_gravity, 3, 'set_target_payload: center_of_gravity')))

    def _payload(self, mass, centre):
        ok, message = self.core.robot.set_payload(float(mass), centre)
        if not ok:
            raise RuntimeFault('set_payload: %s' % message)

    def _set_gravity(self, d):
        direction = _floats(d, 3, 'set_gravity: d')
        length = float(np.linalg.norm(direction))
        if length == 0.0 or np.arccos(min(1.0, direction[2] / length)) > GRAVITY_ALONG_Z:
            raise RuntimeFault('set_gravity: the simulated arm stands upright on its base; it takes gravity '
                               'along the base\'s z axis only, as [0, 0, 9.82], not %s' % to_str(d))

    def _installation_setting(self, name, bound):
        for parameter, allowed in self.settings[name].items():
            if bound[parameter] not in allowed:
                raise RuntimeFault('%s: %s must be %r, not %s' % (name, parameter, allowed, to_str(bound[parameter])))

    def _get_steptime(self):
        return STEP_TIME[self.core.software.generation]

    def _zero_ftsensor(self):
        self.core.zero_tcp_wrench()

    # IO

    def _io(self, what, fun, pin, value):
        ok, message = self.core.robot.set_io(fun, pin, value)
        if not ok:
            raise RuntimeFault('%s: %s' % (what, message))

    def _set_standard_digital_out(self, n, b):
        self._io('set_standard_digital_out', 1, _number('set_standard_digital_out', n, int), 1.0 if b else 0.0)

    _set_digital_out = _set_standard_digital_out

    def _set_configurable_digital_out(self, n, b):
        self._io('set_configurable_digital_out', 1, _number('set_configurable_digital_out', n, int) + CONFIGURABLE_OFFSET,
                 1.0 if b else 0.0)

    def _set_tool_digital_out(self, n, b):
        self._io('set_tool_digital_out', 1, _number('set_tool_digital_out', n, int) + TOOL_OFFSET, 1.0 if b else 0.0)

    def _set_standard_analog_out(self, n, f):
        self._io('set_standard_analog_out', 3, _number('set_standard_analog_out', n, int),
                 _number('set_standard_analog_out', f, float))

    _set_analog_out = _set_standard_analog_out

    def _set_tool_voltage(self, voltage):
        self._io('set_tool_voltage', 4, 0, _number('set_tool_voltage', voltage, float))

    def _pin(self, values, n, offset, count, what):
        n = _number(what, n, int)
        if not 0 <= n < count:
            raise RuntimeFault('%s: pin %d does not exist (0 to %d)' % (what, n, count - 1))
        return values[n + offset]

    def _get_standard_digital_in(self, n):
        return bool(self._pin(self.core.robot.digital_in, n, 0, 8, 'get_standard_digital_in'))

    _get_digital_in = _get_standard_digital_in

    def _get_standard_digital_out(self, n):
        return bool(self._pin(self.core.robot.digital_out, n, 0, 8, 'get_standard_digital_out'))

    _get_digital_out = _get_standard_digital_out

    def _get_configurable_digital_in(self, n):
        return bool(self._pin(self.core.robot.digital_in, n, CONFIGURABLE_OFFSET, 8, 'get_configurable_digital_in'))

    def _get_configurable_digital_out(self, n):
        return bool(self._pin(self.core.robot.digital_out, n, CONFIGURABLE_OFFSET, 8,
                              'get_configurable_digital_out'))

    def _get_tool_digital_in(self, n):
        return bool(self._pin(self.core.robot.digital_in, n, TOOL_OFFSET, 2, 'get_tool_digital_in'))

    def _get_tool_digital_out(self, n):
        return bool(self._pin(self.core.robot.digital_out, n, TOOL_OFFSET, 2, 'get_tool_digital_out'))

    def _get_standard_analog_in(self, n):
        return float(self._pin(self.core.robot.analog_in, n, 0, len(self.core.robot.analog_in),
                               'get_standard_analog_in'))

    _get_analog_in = _get_standard_analog_in

    # the general purpose registers, shared with RTDE clients

    def _register(self, name, address, value=None):
        access, direction, kind = REGISTER_FUNCTIONS[name]
        try:
            if access == 'read':
                return self.core.robot.registers.read(direction, kind, address)
            self.core.robot.registers.write(direction, kind, address, value)
        except RegisterError as error:
            raise RuntimeFault('%s: %s' % (name, error)) from None

    # sockets (script_sockets.py): the robot is the client

    # The MODBUS client (script_modbus.py)

    def _modbus_add_signal(self, IP, slave_number, signal_address, signal_type, signal_name, sequential_mode):
        function = 'modbus_add_signal'
        self.modbus.add_signal(_text(IP, function + ': IP'), _integer(function, slave_number),
                               _integer(function, signal_address), _integer(function, signal_type),
                               _text(signal_name, function + ': signal_name'))

    def _modbus_send_custom_command(self, IP, slave_number, function_code, data):
        function = 'modbus_send_custom_command'
        if not isinstance(data, list):
            raise RuntimeFault('Type error: %s: data is a list of bytes, not %s' % (function, type_name(data)))
        self.modbus.send_custom_command(_text(IP, function + ': IP'), _integer(function, slave_number),
                                        _integer(function, function_code),
                                        [_integer(function, byte) for byte in data])

    def _modbus_delete_signal(self, signal_name):
        self.modbus.delete_signal(_text(signal_name, 'modbus_delete_signal: signal_name'))

    def _modbus_set_signal_update_frequency(self, signal_name, update_frequency):
        function = 'modbus_set_signal_update_frequency'
        self.modbus.set_update_frequency(_text(signal_name, function + ': signal_name'),
                                         _number(function, update_frequency, float))

    def _modbus_get_signal_status(self, signal_name, is_secondary_program):
        return self.modbus.get_status(_text(signal_name, 'modbus_get_signal_status: signal_name'))

    def _modbus_set_output_register(self, signal_name, register_value, is_secondary_program):
        function = 'modbus_set_output_register'
        value = _integer(function, register_value)
        if not 0 <= value <= 65535:
            raise RuntimeFault('%s: %d is not a register value (an unsigned 16-bit integer, 0 to 65535)'
                               % (function, value))
        self.modbus.set_output(function, _text(signal_name, function + ': signal_name'), value, REGISTER_OUTPUT)

    def _modbus_set_output_signal(self, signal_name, digital_value, is_secondary_program):
        function = 'modbus_set_output_signal'
        if not isinstance(digital_value, bool):
            raise RuntimeFault('Type error: %s takes True or False, not %s' % (function, type_name(digital_value)))
        self.modbus.set_output(function, _text(signal_name, function + ': signal_name'), digital_value,
                               DIGITAL_OUTPUT)

    def _socket_open(self, address, port, socket_name):
        return self.sockets.open(_text(address, 'socket_open: address'), port, _text(socket_name, 'socket_name'))

    def _socket_close(self, socket_name):
        self.sockets.close(_text(socket_name, 'socket_name'))

    def _socket_send_string(self, str, socket_name):
        return self.sockets.send(to_str(str).encode('latin-1', 'replace'), _text(socket_name, 'socket_name'))

    def _socket_send_line(self, str, socket_name):
        return self.sockets.send((to_str(str) + '\n').encode('latin-1', 'replace'), _text(socket_name, 'socket_name'))

    def _socket_send_byte(self, value, socket_name):
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 255:
            raise RuntimeFault('socket_send_byte: value must be an integer from 0 to 255, not %s' % to_str(value))
        return self.sockets.send(bytes([value]), _text(socket_name, 'socket_name'))

    def _socket_send_int(self, value, socket_name):
        if isinstance(value, bool) or not isinstance(value, int) or not -2 ** 31 <= value < 2 ** 31:
            raise RuntimeFault('socket_send_int: value must be a 32-bit integer, not %s' % to_str(value))
        return self.sockets.send(struct.pack('>i', value), _text(socket_name, 'socket_name'))

    def _socket_set_var(self, name, value, socket_name):
        self.sockets.send(('SET %s %s\n' % (_text(name, 'socket_set_var: name'), to_str(value))).encode('latin-1'),
                          _text(socket_name, 'socket_name'))

    def _socket_get_var(self, name, socket_name):
        name, socket_name = _text(name, 'socket_get_var: name'), _text(socket_name, 'socket_name')
        self.sockets.send(('GET %s\n' % name).encode('latin-1'), socket_name)
        return self.sockets.read(socket_name, ss.variable(name), ss.READ_TIMEOUT, 0)

    def _socket_read_binary_integer(self, number, socket_name, timeout):
        number = ss.checked_count(number, 'socket_read_binary_integer')
        return self.sockets.read(_text(socket_name, 'socket_name'), ss.binary_integers(number), timeout,
                                 ss.number_failure(number, -1))

    def _socket_read_byte_list(self, number, socket_name, timeout):
        number = ss.checked_count(number, 'socket_read_byte_list')
        return self.sockets.read(_text(socket_name, 'socket_name'), ss.byte_list(number), timeout,
                                 ss.number_failure(number, -1))

    def _socket_read_ascii_float(self, number, socket_name, timeout):
        number = ss.checked_count(number, 'socket_read_ascii_float')
        return self.sockets.read(_text(socket_name, 'socket_name'), ss.ascii_floats(number), timeout,
                                 ss.number_failure(number, math.nan))

    def _socket_read_line(self, socket_name, timeout):
        return self.sockets.read(_text(socket_name, 'socket_name'), ss.line, timeout, '')

    def _socket_read_string(self, socket_name, prefix, suffix, interpret_escape, timeout):
        return self.sockets.read(_text(socket_name, 'socket_name'),
                                 ss.string(_text(prefix, 'prefix'), _text(suffix, 'suffix'), bool(interpret_escape)),
                                 timeout, '')

    # the log and the rest

    def _textmsg(self, s1, s2):
        self.core.program_text(to_str(s1) + to_str(s2))

    def _popup(self, s, title, warning, error, blocking):
        self.core.robot_log('%s: %s' % (to_str(title), to_str(s)))

    def _freedrive_mode(self):
        """Nobody guides the simulated arm by hand: in freedrive it stays where it is."""

    _end_freedrive_mode = _teach_mode = _end_teach_mode = _freedrive_mode
