"""The simulated arm's settings: its node's parameters and the model, checked, without ROS.

Read through `get_param(name, default)` (rospy.get_param on the node, a dict
in tests). What a user can get wrong is one ParamError line naming the
parameter and what it must be.
"""

import math

import numpy as np

from .. import sim_params
from . import controller_manager as cm
from . import robot_state as rs
from . import software
from .arm_kinematics import ArmKinematics


class Settings(object):
    """What the node's parameters and robot_description say, checked."""


def read_settings(get_param):
    """Settings from `get_param(name, default)` (rospy.get_param, or a dict in tests); ParamError on bad input."""
    settings = Settings()
    settings.prefix = sim_params.prefix(get_param)
    ur_type = get_param('~ur_type', 'ur5e')
    if not isinstance(ur_type, str) or not ur_type:
        raise sim_params.ParamError('~ur_type=%r must be a UR model name, e.g. ur5e' % (ur_type,))
    settings.ur_type = ur_type
    try:
        settings.software = software.for_model(ur_type)
    except software.UnknownModel as exc:
        raise sim_params.ParamError('~ur_type: %s' % exc)
    config_file = sim_params.existing_file(get_param, '~controller_config_file', None)
    try:
        config = cm.read_config(config_file)
        sections, joints = cm.controller_sections(config)
        config_hz = float(config.get('hardware_control_loop', {}).get('loop_hz', 125))
        settings.loop_hz = sim_params.number(get_param, '~loop_hz', config_hz, strictly_above=0.0)
    except cm.ControllerConfigError as exc:
        raise sim_params.ParamError('~controller_config_file: %s' % exc)
    settings.joints = [name if name.startswith(settings.prefix) else settings.prefix + name for name in joints]
    started = str(get_param('~controllers', '')).split()
    stopped = get_param('~stopped_controllers', '')
    stopped = str(stopped).split() if stopped else [n for n in sections if n not in started and
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
    # Elbow bent, tool pointing down: away from the singularities of the stretched arm.
    initial = get_param('~initial_positions', [0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0])
    try:
        initial = np.array(initial, dtype=float)
    except (TypeError, ValueError):
        initial = np.array([])
    if initial.shape != (6,) or not np.all(np.isfinite(initial)) or np.any(initial < settings.arm.lower) or \
            np.any(initial > settings.arm.upper):
        raise sim_params.ParamError('~initial_positions=%r must be six finite joint positions within the '
                                    'model\'s limits (rad)' % (get_param('~initial_positions', None),))
    settings.initial = initial
    settings.servo_lag = sim_params.number(get_param, '~servoj_lookahead_time', 0.03, minimum=0.0)
    mode = get_param('~robot_mode', 'RUNNING')
    if mode not in rs.SELECTABLE_MODES:
        raise sim_params.ParamError('~robot_mode=%r: use POWER_OFF, IDLE or RUNNING' % (mode,))
    settings.robot = rs.RobotState(settings.software, robot_mode=mode,
                                   program_running=bool(get_param('~program_running', True)),
                                   headless=bool(get_param('~headless_mode', False)))
    return settings
