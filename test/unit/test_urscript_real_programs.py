"""Programs as PolyScope and the drivers write them, run on the simulated arm's core (core.ArmCore).

The programs are test/data/urscript/real/*.script: PolyScope exports (the
installation header PolyScope writes first, program labels `$ n "text"`) for
each generation, and a driver-style servo stream whose threads share their
command inside critical sections. Each test states what the robot must hold
after the program: outputs, payload, TCP, the joints, the log.
"""
import math
import os

import numpy as np
import pytest
import rospkg

from ur3_ft_gripper_testing.model import PACKAGE_DIR

from ur3_ft_gripper_description import urscript
from ur3_ft_gripper_description.devices.ur_arm import core as arm_core
from ur3_ft_gripper_description.devices.ur_arm import joints as jm
from ur3_ft_gripper_description.devices.ur_arm import robot_state as rs
from ur3_ft_gripper_description.devices.ur_arm import script_robot
from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings

PROGRAMS = os.path.join(PACKAGE_DIR, 'test', 'data', 'urscript', 'real')
# The controllers' time steps: CB3 125 Hz, e-Series 500 Hz.
STEP_TIME = {'ur3': 0.008, 'ur5e': 0.002}
HOME = [0.3, -1.4, 1.6, -1.8, -1.57, 0.2]  # the exports' Home waypoint
# The installation header's setters PolyScope writes (5.x and 3.x programs).
HEADER = ['set_gravity', 'set_tool_voltage', 'set_safety_mode_transition_hardness', 'set_analog_outputdomain',
          'set_standard_analog_input_domain', 'set_tool_analog_input_domain', 'set_input_actions_to_default',
          'set_tool_communication', 'set_tool_output_mode', 'set_tool_digital_output_mode', 'set_target_payload',
          'set_payload', 'set_tcp']
E_SERIES_TOOL_FLANGE = ['set_tool_communication', 'set_tool_output_mode', 'set_tool_digital_output_mode']


def program(name):
    with open(os.path.join(PROGRAMS, name)) as f:
        return f.read()


def make_core(configured_model, ur_type):
    config = os.path.join(rospkg.RosPack().get_path('ur_robot_driver'), 'config', '%s_controllers.yaml' % ur_type)
    values = {'~ur_type': ur_type, '~controller_config_file': config,
              'robot_description': configured_model(ur_type, False, False).text,
              '~controllers': 'joint_state_controller scaled_pos_joint_traj_controller'}
    settings = read_settings(lambda name, default=None: values.get(name, default))
    return arm_core.ArmCore(settings, jm.KinematicJoints.from_settings(settings)), 1.0 / settings.loop_hz


def run(core, dt, text, seconds=20.0):
    """Sends the program as script_command does and steps until it stops; the core's messages."""
    core.script_command(text)
    cycles = 0
    while core.script_running:
        assert cycles * dt < seconds, 'still running after %g s' % seconds
        core.step(dt)
        cycles += 1
    return core.take_messages()


def logged(core, name):
    """The value after `name ` in the robot's log line that starts with it."""
    line = next(text for text in core.robot.log if text.startswith(name + ' '))
    return line[len(name) + 1:]


def errors(messages):
    return [text for level, text in messages if level == arm_core.ERROR]


@pytest.mark.parametrize('ur_type, name', [('ur5e', 'polyscope_e_series.script'), ('ur3', 'polyscope_cb3.script')])
def test_a_polyscope_export_with_its_header_and_labels_runs_to_the_robot_state_it_sets(configured_model, ur_type,
                                                                                     name):
    core, dt = make_core(configured_model, ur_type)
    messages = run(core, dt, program(name))
    assert errors(messages) == [] and core.robot.program_state == rs.STOPPED
    robot = core.robot
    assert robot.tool_voltage == 24 and robot.payload == (1.2, (0.0, 0.0, 0.06))
    assert robot.digital_out[2] and robot.digital_out[script_robot.TOOL_OFFSET]
    assert np.allclose(core.tcp[:3, 3], [0, 0, 0.15]) and np.allclose(core.tcp[:3, :3], np.eye(3))
    # The loop ran twice, and ended at Home.
    assert float(logged(core, 'picked')) == 2
    assert np.allclose(core.motion.position, HOME, atol=1e-6)
    assert float(logged(core, 'step time')) == STEP_TIME[ur_type]


def test_the_e_series_header_is_refused_on_a_cb3_naming_the_tool_flange_setter(configured_model):
    core, dt = make_core(configured_model, 'ur3')
    text = program('polyscope_e_series.script')
    line = next(n for n, source in enumerate(text.splitlines(), 1) if 'set_tool_communication' in source)
    messages = run(core, dt, text)
    assert errors(messages) == ['script_command: the robot would not compile this script: line %d: '
                                'set_tool_communication is a URScript function the simulated robot does not offer'
                                % line]
    assert core.robot.tool_voltage == 0 and list(core.robot.log) == []


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e'])
def test_every_header_setter_of_the_manual_is_served_or_refused_by_name(configured_model, ur_type):
    core, _ = make_core(configured_model, ur_type)
    served = core.script_robot.served()
    assert set(HEADER) <= urscript.MANUAL_FUNCTIONS and 'get_steptime' in served
    refused = sorted(name for name in HEADER if name not in served)
    if ur_type == 'ur3':
        assert refused == sorted(E_SERIES_TOOL_FLANGE + ['set_target_payload'])
    else:
        assert refused == ['set_target_payload']  # 5.10 on: the simulated e-Series runs 5.9
    for name in refused:
        with pytest.raises(urscript.CompileError) as caught:
            urscript.compile_script('%s()\n' % name, served)
        assert str(caught.value) == 'line 1: %s is a URScript function the simulated robot does not offer' % name


@pytest.mark.parametrize('call, error', [
    ('set_gravity([0, 9.82, 0])', "set_gravity: the simulated arm stands upright on its base; it takes gravity "
                                  "along the base's z axis only, as [0, 0, 9.82], not [0, 9.82, 0]"),
    ('set_analog_outputdomain(2, 0)', 'set_analog_outputdomain: port must be 0 or 1, not 2'),
    ('set_tool_digital_output_mode(0, 0)', 'set_tool_digital_output_mode: mode must be 1 or 2 or 3, not 0'),
    ('set_tool_communication(1, 115200, 0, 1, 1.5, 3.5)',
     'set_tool_communication: enabled must be False or True, not 1'),
    ('set_tool_communication(True, 115200, 0, 1, 0.5, 3.5)',
     'set_tool_communication: rx_idle_chars must be a number >= 1, not 0.5'),
    ('set_safety_mode_transition_hardness(True)', 'set_safety_mode_transition_hardness: type must be 0 or 1, '
                                                  'not True'),
])
def test_a_header_setting_outside_the_manuals_values_stops_the_program_naming_it(configured_model, call, error):
    core, dt = make_core(configured_model, 'ur5e')
    messages = run(core, dt, 'textmsg("before")\n%s\ntextmsg("after")\n' % call)
    assert core.robot.log[0] == 'before' and 'after' not in core.robot.log
    assert core.robot.log[-1] == 'RuntimeException: Runtime error in line 2, column 1 Error: %s' % error
    assert len(errors(messages)) == 1


@pytest.mark.parametrize('ur_type', ['ur3', 'ur5e'])
def test_a_driver_servo_stream_shares_its_command_in_critical_sections_and_follows_it(configured_model, ur_type):
    core, dt = make_core(configured_model, ur_type)
    messages = run(core, dt, program('driver_servo.script'))
    assert errors(messages) == []
    # Each target handed over was taken once by the servo thread, whose servoj waits (physical time)
    # inside its critical section let main run; the arm ends on the last target.
    assert float(logged(core, 'received')) == 3
    last = [0.3, -1.3, 1.3, -1.3, -1.3, 0.3]
    assert np.allclose(core.motion.position, last, atol=1e-4)
    assert np.allclose([float(v) for v in logged(core, 'at')[1:-1].split(',')], last, atol=1e-4)
    assert math.isclose(core.script_robot.call('get_steptime', [], {}), STEP_TIME[ur_type])
