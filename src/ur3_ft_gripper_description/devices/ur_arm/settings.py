"""The simulated UR controller's settings (node ur_hardware_interface): its parameters and the model, checked.

The node (ur_hardware_interface) declares its private parameters in
PARAMETERS here, ~physics and ~world_file with the physics cell's
(physics/arm_cell.py); their reference is doc/node_parameters.md. Read
through `get_param(name, default)` (rospy.get_param on the node, a dict in
tests); no ROS needed. What a user can get wrong is one ParamError line
naming the parameter and what it must be.
"""

import ipaddress
import math
import re

import numpy as np

from .. import sim_clock, sim_params
from ..network import listen
from ..wrench_model import load_sensor_spec
from ..physics import arm_cell
from . import controller_manager as cm
from . import robot_state as rs
from . import software
from ...model.names import FLANGE
from .arm_kinematics import ArmKinematics
from .tcp_wrench import mounted_payload


def ur_model_name(name, value):
    if not isinstance(value, str) or not value:
        raise sim_params.ParamError('%s=%r must be a UR model name, e.g. ur5e' % (name, value))
    return value


def selectable_mode(name, value):
    if value not in rs.SELECTABLE_MODES:
        raise sim_params.ParamError('%s=%r: use POWER_OFF, IDLE or RUNNING' % (name, value))
    return value


def words(name, value):
    """Names separated by spaces; empty: none."""
    return str(value).split() if value else []


def socket_hosts(name, value):
    """IPv4 addresses or networks, separated by commas or spaces; empty: none."""
    hosts = []
    for word in re.split(r'[,\s]+', str(value or '').strip()):
        if not word:
            continue
        try:
            network = ipaddress.ip_network(word, strict=False)
        except ValueError:
            network = None
        if network is None or network.version != 4:
            raise sim_params.ParamError('%s=%s: %r is not an IPv4 address or network; give addresses or networks such '
                                        'as 192.168.56.1 or 192.168.56.0/24, separated by commas' % (name, value, word))
        hosts.append(network)
    return hosts


def robot_ip(name, value):
    """An IPv4 address, or empty for no network interfaces."""
    if value in ('', None):
        return ''
    try:
        return listen.checked_address(value)
    except listen.ListenError as exc:
        raise sim_params.ParamError('%s=%s' % (name, exc)) from None


PARAMETERS = (
    sim_params.PREFIX,
    sim_params.Param('~ur_type', 'ur5e', 'UR model (ur3, ur5e, ...): its software version and CB3 or e-Series '
                     'behaviour', ur_model_name),
    sim_params.Param('~controller_config_file', None, "ur_robot_driver's controller configuration "
                     '(config/<ur_type>_controllers.yaml): the controllers, their joints and loop_hz; required',
                     sim_params.existing_file),
    sim_params.Param('~loop_hz', sim_params.StartupDefault('`hardware_control_loop/loop_hz` of '
                                                           '~controller_config_file, else 125'),
                     'Control loop and joint_states rate (Hz)', sim_params.number(strictly_above=0.0)),
    sim_params.Param('~controllers', '', 'Controllers started at start-up, separated by spaces', words),
    sim_params.Param('~stopped_controllers', '', 'Controllers loaded but not started, separated by spaces; '
                     'empty: every other simulated controller of the configuration', words),
    sim_params.Param('~initial_positions', [0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0],
                     'The six joint positions at start-up (rad), within the model\'s limits; the default '
                     '(0, -pi/2, pi/2, -pi/2, -pi/2, 0): elbow bent and tool pointing down, away from the '
                     'singularities of the stretched arm'),
    sim_params.Param('~servoj_lookahead_time', 0.03, "As ur_robot_driver's: the joints follow their commands with "
                     'this time constant (s); 0: at once', sim_params.number(minimum=0.0)),
    sim_params.Param('~robot_mode', 'RUNNING', 'Robot mode at start-up: POWER_OFF, IDLE or RUNNING',
                     selectable_mode),
    sim_params.Param('~program_running', True, 'The external control program runs at start-up (in RUNNING)',
                     sim_params.flag),
    sim_params.Param('~headless_mode', False, "As ur_robot_driver's: resend_robot_program starts the program "
                     '(true) or dashboard play does (false)', sim_params.flag),
    sim_params.Param('~robot_ip', '', "The controller's own network interfaces (the Dashboard Server on 29999, primary and secondary 30001-30002, real-time 30003, RTDE 30004) "
                     'listen on this IPv4 address, e.g. 127.0.0.1, or 127.0.0.2 for a second cell on the machine; '
                     'empty: none', robot_ip),
    sim_params.Param('~script_modbus_port', 502, "The port of the units URScript's MODBUS client (modbus_add_signal) "
                     "polls: the robot's is always Modbus TCP's 502; another for a unit that cannot take 502 (a "
                     'server without root, the simulated gripper\'s gateway at sim_gripper_gateway_port)',
                     sim_params.number(minimum=1.0)),
    sim_params.Param('~script_socket_hosts', '', "Addresses beyond this machine's loopback that URScript's "
                     'socket_open, rpc_factory and modbus_* functions may connect to: IPv4 addresses or networks '
                     '(192.168.56.1, 192.168.56.0/24) separated by commas; empty: loopback only', socket_hosts),
) + arm_cell.PARAMETERS + sim_clock.PARAMETERS


class Settings(object):
    """What the node's parameters and robot_description say, checked."""


def read_settings(get_param):
    """Settings from `get_param(name, default)` (rospy.get_param, or a dict in tests); ParamError on bad input."""
    def param(name, **default):
        return sim_params.read(get_param, PARAMETERS, name, **default)
    settings = Settings()
    settings.prefix = param('~prefix')
    ur_type = settings.ur_type = param('~ur_type')
    try:
        settings.software = software.for_model(ur_type)
    except software.UnknownModel as exc:
        raise sim_params.ParamError('~ur_type: %s' % exc)
    config_file = param('~controller_config_file')
    try:
        config = cm.read_config(config_file)
        sections, joints = cm.controller_sections(config)
        config_hz = float(config.get('hardware_control_loop', {}).get('loop_hz', 125))
        settings.loop_hz = param('~loop_hz', default=config_hz)
    except cm.ControllerConfigError as exc:
        raise sim_params.ParamError('~controller_config_file: %s' % exc)
    settings.joints = [name if name.startswith(settings.prefix) else settings.prefix + name for name in joints]
    started = param('~controllers')
    stopped = param('~stopped_controllers') or [n for n in sections if n not in started and
                                                 sections[n]['type'] in cm.SIMULATED_TYPES]
    try:
        settings.manager = cm.ControllerManager(sections, settings.joints, started, stopped)
    except cm.ControllerConfigError as exc:
        raise sim_params.ParamError('~controllers / ~stopped_controllers: %s' % exc)
    description = get_param('robot_description', None)
    if not isinstance(description, str):
        raise sim_params.ParamError('robot_description is not set: load the model first (load_ur_ft_gripper.launch)')
    try:
        settings.arm = ArmKinematics(description, settings.joints, settings.prefix + 'base',
                                     settings.prefix + 'tool0')
    except (ValueError, KeyError) as exc:
        raise sim_params.ParamError('robot_description: %s (is ~prefix %r the model\'s?)' % (exc, settings.prefix))
    given = param('~initial_positions')
    try:
        initial = np.array(given, dtype=float)
    except (TypeError, ValueError):
        initial = np.array([])
    if initial.shape != (6,) or not np.all(np.isfinite(initial)) or np.any(initial < settings.arm.lower) or \
            np.any(initial > settings.arm.upper):
        raise sim_params.ParamError('~initial_positions=%r must be six finite joint positions within the '
                                    'model\'s limits (rad)' % (given,))
    settings.initial = initial
    settings.servo_lag = param('~servoj_lookahead_time')
    # /use_sim_time is ROS's own global parameter (rospy reads it too), not the node's.
    settings.use_sim_time = sim_params.flag('/use_sim_time', get_param('/use_sim_time', False))
    settings.real_time_factor = sim_clock.check_factor(settings.use_sim_time, param('~real_time_factor'))
    settings.clock_stride = sim_clock.clock_stride(settings.use_sim_time, settings.loop_hz,
                                                   param('~pub_clock_frequency'),
                                                   load_sensor_spec(sim_params.SIM_DEVICES_FILE.path()).rate)
    mode = param('~robot_mode')
    settings.robot = rs.RobotState(settings.software, robot_mode=mode, program_running=param('~program_running'),
                                   headless=param('~headless_mode'))
    # The installation's payload: what the model mounts on the flange, as a user enters it on the teach pendant.
    settings.robot.payload = mounted_payload(description, settings.prefix + FLANGE)
    settings.robot_ip = param('~robot_ip')
    settings.script_socket_hosts = param('~script_socket_hosts')
    settings.script_modbus_port = param('~script_modbus_port')
    if settings.script_modbus_port != int(settings.script_modbus_port) or settings.script_modbus_port > 65535:
        raise sim_params.ParamError('~script_modbus_port=%r: use a TCP port, 1 to 65535'
                                    % (settings.script_modbus_port,))
    return settings
