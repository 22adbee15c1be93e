"""The simulated controller's side of RTDE: the value of each output field and what each input does; no ROS.

The RTDE guide names the fields and their types (config/rtde_variables.yaml,
read by network/rtde.py); here each output is a function of the core after
a cycle and of that cycle's Snapshot, the same numbers the ROS face
publishes (joint_states' effort is the driver's actual_current, its wrench
the robot's TCP force), and each input a change to the robot.

Quantities the twin does not model (temperatures, voltages, Euromap 67)
read as the constant of UNMODELLED, with the reason: the table of the guide
is served whole, and a test checks that every field is either computed here
or listed there.
"""

import numpy as np

from . import robot_state as rs
from . import tool_motion as tm
from ..wrench_model import STANDARD_GRAVITY as GRAVITY  # the twin's own, as its wrench model weighs
from .registers import BOOLEAN, FLOAT, INTEGER

# RTDE guide: robot_mode, safety_mode and runtime_state numbers (the same as ur_dashboard_msgs').
ROBOT_MODE = {rs.POWER_OFF: 3, rs.BOOTING: 2, rs.POWER_ON: 4, rs.IDLE: 5, rs.RUNNING: 7}
SAFETY_MODE = {rs.SAFETY_NORMAL: 1, rs.PROTECTIVE_STOP: 3}
RUNTIME_STATE = {rs.STOPPED: 1, rs.PLAYING: 2, rs.PAUSED: 4}
# Joint and tool modes of the client interface manual: running, idle (brakes on), powered off, booting.
JOINT_MODE = {rs.RUNNING: 253, rs.IDLE: 255, rs.POWER_ON: 255, rs.BOOTING: 247, rs.POWER_OFF: 239}
TOOL_MODE = {True: 253, False: 255}
# safety_status_bits: bit of each safety mode (normal 0, reduced 1, protective stop 2, ...).
SAFETY_BIT = {rs.SAFETY_NORMAL: 0, rs.PROTECTIVE_STOP: 2}
# analog_io_types: 1 = voltage, per pin (bits 0-1 standard inputs, 2-3 standard outputs); the ROS face
# reports the inputs as voltages and the outputs as currents.
ANALOG_IO_TYPES = 0b0011

# name: (value, why it is a constant)
UNMODELLED = {
    'joint_temperatures': ([30.0] * 6, 'no thermal model: a warm joint at rest'),
    'actual_execution_time': (0.3, 'ms; the twin has no real-time thread to measure'),
    'actual_momentum': (0.0, 'no link inertia model outside physics'),
    'actual_main_voltage': (48.0, 'the control box\'s 48 V supply'),
    'actual_robot_voltage': (48.0, 'the arm\'s 48 V bus'),
    'actual_robot_current': (0.0, 'no power model'),
    'actual_joint_voltage': ([48.0] * 6, 'the arm\'s 48 V bus'),
    'io_current': (0.0, 'no IO power model'),
    'tool_analog_input_types': (0, 'current inputs, nothing wired'),
    'tool_analog_input0': (0.0, 'nothing wired to the tool\'s analog inputs'),
    'tool_analog_input1': (0.0, 'nothing wired to the tool\'s analog inputs'),
    'tool_output_current': (0.0, 'no power model'),
    'tool_temperature': (30.0, 'no thermal model'),
    'joint_position_deviation_ratio': (0.0, 'no deviation model'),
    'script_control_line': (0, 'the line of a program is not tracked'),
    'encoder0_raw': (0, 'no encoders wired'),
    'encoder1_raw': (0, 'no encoders wired'),
    'tool_output_mode': (0, 'the tool\'s outputs as digital outputs, set_tool_output_mode\'s default'),
    'tool_digital_output0_mode': (1, 'sinking (NPN), the tool\'s default'),
    'tool_digital_output1_mode': (1, 'sinking (NPN), the tool\'s default'),
    'collision_detection_ratio': (0.0, 'no collision detection model (physics stops by force limits instead)'),
    'time_scale_source': (-1, 'the scaling\'s reason is not tracked: "other"'),
    'target_base_acceleration': ([0.0] * 6, 'the base stands still'),
    'target_base_wrench': ([0.0] * 6, 'no base wrench model'),
    'euromap67_input_bits': (0, 'no Euromap 67 interface'),
    'euromap67_output_bits': (0, 'no Euromap 67 interface'),
    'euromap67_24V_voltage': (0.0, 'no Euromap 67 interface'),
    'euromap67_24V_current': (0.0, 'no Euromap 67 interface'),
}


def _bits(flags):
    return sum(1 << i for i, flag in enumerate(flags) if flag)


def _pose(matrix):
    return tm.ur_pose_of(matrix)


def _elbow_position(core, snapshot):
    """The elbow joint's origin in the base (the third joint of the chain)."""
    return [float(v) for v in core.arm.joint_axes(snapshot.position)[1][2]]


def _elbow_velocity(core, snapshot):
    """The elbow's velocity: the shoulder joints' turns about their axes, at the elbow."""
    qd = snapshot.velocity
    if not np.any(qd[:2]):
        return [0.0, 0.0, 0.0]  # at rest: no kinematics needed
    axes, points = core.arm.joint_axes(snapshot.position)
    return [float(v) for v in qd[0] * np.cross(axes[0], points[2] - points[0]) +
            qd[1] * np.cross(axes[1], points[2] - points[1])]


def _register_bits(registers, direction, first):
    return _bits(getattr(registers, direction)[BOOLEAN][first:first + 32])


def _registers(name):
    """The reader of a register field's value, or None if `name` is not one."""
    for direction in ('input', 'output'):
        for prefix, kind in (('_bit_register_', BOOLEAN), ('_int_register_', INTEGER), ('_double_register_', FLOAT)):
            if name.startswith(direction + prefix):
                index = int(name[len(direction + prefix):])
                return lambda c, s: c.robot.registers.read(direction, kind, index)
        for first in (0, 32):
            if name == '%s_bit_registers%d_to_%d' % (direction, first, first + 31):
                return lambda c, s: _register_bits(c.robot.registers, direction, first)
    return None


def _tcp_speed(core, q, qd):
    if not np.any(qd):
        return [0.0] * 6  # at rest: no kinematics needed
    return [float(v) for v in tm.tcp_jacobian(core.arm, core.tcp, q).dot(qd)]


def _target_pose(core, snapshot):
    if np.array_equal(core.target_position, snapshot.position):
        return _pose(snapshot.tool_pose)  # holding where it is: the actual pose, already computed
    return _pose(tm.tcp_pose(core.arm, core.tcp, core.target_position))


def _flange_in_base(core):
    wrench = core.motion.flange_wrench
    if wrench is None:
        return [0.0] * 6
    rotation = core.arm.forward(core.motion.position)[:3, :3]
    return [float(v) for v in np.concatenate([rotation.dot(wrench[:3]), rotation.dot(wrench[3:])])]


# name: function(core, snapshot) of the value after the cycle.
COMPUTED = {
    'timestamp': lambda c, s: c.uptime,
    'target_q': lambda c, s: c.target_position.tolist(),
    'target_qd': lambda c, s: c.target_velocity.tolist(),
    'target_qdd': lambda c, s: [0.0] * 6,
    'target_current': lambda c, s: s.effort.tolist(),
    'target_moment': lambda c, s: s.effort.tolist(),
    'actual_q': lambda c, s: s.position.tolist(),
    'actual_qd': lambda c, s: s.velocity.tolist(),
    'actual_current': lambda c, s: s.effort.tolist(),
    'actual_current_window': lambda c, s: [0.0] * 6,
    'actual_current_as_torque': lambda c, s: s.effort.tolist(),
    'joint_control_output': lambda c, s: s.effort.tolist(),
    'actual_TCP_pose': lambda c, s: _pose(s.tool_pose),
    'actual_TCP_speed': lambda c, s: _tcp_speed(c, s.position, s.velocity),
    'actual_TCP_force': lambda c, s: [float(v) for v in c.tcp_force()[0]],
    'target_TCP_pose': _target_pose,
    'target_TCP_speed': lambda c, s: _tcp_speed(c, c.target_position, c.target_velocity),
    'ft_raw_wrench': lambda c, s: _flange_in_base(c),
    'tcp_offset': lambda c, s: _pose(c.tcp),
    'elbow_position': _elbow_position,
    'elbow_velocity': _elbow_velocity,
    'actual_tool_accelerometer': lambda c, s: [float(v) for v in s.tool_pose[:3, :3].T.dot([0.0, 0.0, GRAVITY])],
    'actual_digital_input_bits': lambda c, s: _bits(s.digital_in),
    'actual_digital_output_bits': lambda c, s: _bits(s.digital_out),
    'actual_configurable_digital_input_bits': lambda c, s: _bits(s.digital_in[8:16]),
    'actual_configurable_digital_output_bits': lambda c, s: _bits(s.digital_out[8:16]),
    'tcp_force_scalar': lambda c, s: float(np.linalg.norm(c.tcp_force()[0][:3])),
    'target_gravity': lambda c, s: [0.0, 0.0, -GRAVITY],
    'control_step': lambda c, s: int(round(c.uptime / c.script_robot.call('get_steptime', [], {}))),
    'robot_mode': lambda c, s: ROBOT_MODE[s.robot_mode],
    'joint_mode': lambda c, s: [JOINT_MODE[s.robot_mode]] * 6,
    'safety_mode': lambda c, s: SAFETY_MODE[s.safety_mode],
    'safety_status': lambda c, s: SAFETY_MODE[s.safety_mode],
    'safety_status_bits': lambda c, s: 1 << SAFETY_BIT[s.safety_mode] | (s.safety_mode != rs.SAFETY_NORMAL) << 10,
    'robot_status_bits': lambda c, s: _bits([s.robot_mode != rs.POWER_OFF, c.robot.program_state == rs.PLAYING]),
    'runtime_state': lambda c, s: RUNTIME_STATE[c.robot.program_state],
    'speed_scaling': lambda c, s: float(s.speed_scaling),
    'target_speed_fraction': lambda c, s: c.robot.speed_slider,
    'standard_analog_input0': lambda c, s: s.analog_in[0],
    'standard_analog_input1': lambda c, s: s.analog_in[1],
    'standard_analog_output0': lambda c, s: s.analog_out[0],
    'standard_analog_output1': lambda c, s: s.analog_out[1],
    'analog_io_types': lambda c, s: ANALOG_IO_TYPES,
    'tool_mode': lambda c, s: TOOL_MODE[s.tool_running],
    'tool_output_voltage': lambda c, s: int(s.tool_voltage),
    'payload': lambda c, s: c.robot.payload[0],
    'payload_cog': lambda c, s: list(c.robot.payload[1]),
    'payload_inertia': lambda c, s: [0.0] * 6,
}


# Quantities of the controller beyond RTDE's fields, which its other interfaces report (the primary
# interface's robot state: config/ur_primary_interface.yaml's sources).
# ur_client_library's robot types (datatypes.h): an e-Series model has its CB3 namesake's number.
ROBOT_TYPE = {'ur5': 1, 'ur10': 2, 'ur3': 3, 'ur16': 4, 'ur20': 7, 'ur30': 8}
# UR's joint acceleration limit as URSim 5.8 reports it for every joint (rad/s^2).
JOINT_ACCELERATION_LIMIT = 40.0


def _interleaved(first, second):
    return [float(v) for pair in zip(first, second) for v in pair]


CONTROLLER = {
    'clock_ms': lambda c, s: int(round(c.uptime * 1000.0)),
    'power_on': lambda c, s: s.robot_mode != rs.POWER_OFF,
    'protective_stopped': lambda c, s: s.safety_mode == rs.PROTECTIVE_STOP,
    'program_running': lambda c, s: c.robot.program_state == rs.PLAYING,
    'program_paused': lambda c, s: c.robot.program_state == rs.PAUSED,
    'control_mode': lambda c, s: 2 if c.script_robot.force is not None else 0,  # POSITION 0, FORCE 2
    'dh_theta': lambda c, s: [0.0] * 6,
    'dh_a': lambda c, s: [float(v) for v in c.arm.nominal.a],
    'dh_d': lambda c, s: [float(v) for v in c.arm.nominal.d],
    'dh_alpha': lambda c, s: list(c.arm.nominal.ALPHA),
    'joint_position_limits': lambda c, s: _interleaved(c.arm.lower, c.arm.upper),
    'joint_speed_acceleration_limits': lambda c, s: _interleaved(c.arm.velocity, [JOINT_ACCELERATION_LIMIT] * 6),
    'robot_type': lambda c, s: ROBOT_TYPE[c.software.ur_type.rstrip('e')],
    # URSim 5.8's UR5e (ur_client_library's capture); the CB3's are not documented.
    'masterboard_version': lambda c, s: 6,
    'controller_box_type': lambda c, s: 4,
    'robot_sub_type': lambda c, s: 3,
}


def reader(name):
    """function(core, snapshot) -> the value of output field `name` (or controller quantity), or None if
    the twin has none."""
    if name in COMPUTED:
        return COMPUTED[name]
    if name in CONTROLLER:
        return CONTROLLER[name]
    if name in UNMODELLED:
        value = UNMODELLED[name][0]
        return lambda c, s: value
    return _registers(name)


# -- inputs ------------------------------------------------------------------------------------------

def _masked_pins(core, values, mask_name, value_name, offset, count):
    mask, bits = values.get(mask_name), values.get(value_name)
    if mask is None or bits is None:
        return
    for pin in range(count):
        if mask >> pin & 1:
            core.set_io(1, offset + pin, float(bits >> pin & 1))


def apply_inputs(core, values):
    """One input data package, {field name: value}, applied to the robot at once, as the controller does."""
    registers = core.robot.registers
    for name in values:
        core.rtde_input_times[name] = core.uptime
    for name, value in values.items():
        for prefix, kind in (('input_bit_register_', BOOLEAN), ('input_int_register_', INTEGER),
                             ('input_double_register_', FLOAT)):
            if name.startswith(prefix):
                registers.write('input', kind, int(name[len(prefix):]), value)
        for first in (0, 32):
            if name == 'input_bit_registers%d_to_%d' % (first, first + 31):
                for bit in range(32):
                    registers.write('input', BOOLEAN, first + bit, bool(value >> bit & 1))
    if values.get('speed_slider_mask', 0) & 1 and 'speed_slider_fraction' in values:
        core.set_speed_slider(values['speed_slider_fraction'])
    _masked_pins(core, values, 'standard_digital_output_mask', 'standard_digital_output', 0, 8)
    _masked_pins(core, values, 'configurable_digital_output_mask', 'configurable_digital_output', 8, 8)
    _masked_pins(core, values, 'tool_digital_output_mask', 'tool_digital_output', 16, 2)
    mask = values.get('standard_analog_output_mask', 0)
    for pin in range(2):
        name = 'standard_analog_output_%d' % pin
        if mask >> pin & 1 and name in values:
            core.set_io(3, pin, values[name])
