"""The robot functions a client's control program calls, run on the simulated arm's core (core.ArmCore).

ur_rtde's RTDEControlInterface sends the robot a program that waits for commands in RTDE's registers and
calls, besides the motions, the robot's queries and set-ups: the joints' history, the target waypoint,
the payload, the safety limits, a protective stop, an RTDE watchdog, servoc, tool_contact and the
external F/T sensor's switches. Each test holds the robot's answer to a known truth: a constant speed's
travel, the pose a move was given, the joint limits, the watchdog's period. ur_rtde itself drives them in
test/consumers/test_ur_rtde.py.
"""
import pytest

from ur3_ft_gripper_description.devices.ur_arm import robot_state as rs

from controller_cell import Cell
from test_urscript_real_programs import errors, make_core, run

UR_TYPES = ['ur3', 'ur5e']


@pytest.fixture(params=UR_TYPES)
def cell(request, configured_model):
    return make_core(configured_model, request.param)


def test_the_joints_history_holds_each_cycle_back(cell):
    core, dt = cell
    speed, steps = 0.2, 10
    run(core, dt, 'speedj([%g, 0, 0, 0, 0, 0], 1.0, 0.5)\n'
                  'now = get_actual_joint_positions()\n'
                  'back = get_actual_joint_positions_history(%d)\n'
                  'textmsg(now[0] - back[0])\n'
                  'stopj(2)\n' % (speed, steps))
    # 0.5 s after a ramp of 0.2 s the joint turns at its speed: `steps` cycles back it was that much behind.
    assert float(core.robot.log[0]) == pytest.approx(speed * steps * dt, rel=1e-9)


def test_a_history_step_past_the_kept_second_stops_the_program_naming_the_bound(cell):
    core, dt = cell
    messages = run(core, dt, 'sync()\nx = get_actual_joint_positions_history(%d)\n' % int(round(1.0 / dt)))
    assert errors(messages) == ['script_command: RuntimeException: Runtime error in line 2, column 5 Error: '
                                'get_actual_joint_positions_history: steps must be an integer from 0 to %d (the '
                                'history the simulated robot keeps), not %d; program stopped'
                                % (int(round(1.0 / dt)) - 1, int(round(1.0 / dt)))]


def test_the_target_waypoint_is_the_moves_end_while_it_runs_and_the_target_pose_at_rest(cell):
    core, dt = cell
    run(core, dt, 'start = get_actual_tcp_pose()\n'
                  'goal = pose_add(start, p[0, 0, 0.05, 0, 0, 0])\n'
                  'global seen = p[0, 0, 0, 0, 0, 0]\n'
                  'thread watch():\n  sleep(0.1)\n  seen = get_target_waypoint()\nend\n'
                  'run watch()\n'
                  'movel(goal, a=1.2, v=0.1)\n'
                  'textmsg(pose_dist(seen, goal))\n'
                  'textmsg(pose_dist(get_target_waypoint(), goal))\n'
                  'textmsg(pose_dist(seen, start))\n')
    during, after, from_start = (float(v) for v in list(core.robot.log)[:3])
    assert during == pytest.approx(0.0, abs=1e-9) and after == pytest.approx(0.0, abs=1e-6)
    assert from_start == pytest.approx(0.05, abs=1e-9)


def test_servoc_takes_the_tcp_to_the_pose(cell):
    core, dt = cell
    run(core, dt, 'goal = pose_add(get_actual_tcp_pose(), p[0.03, 0, -0.02, 0, 0, 0])\n'
                  'servoc(goal, a=1.2, v=0.25)\n'
                  'textmsg(pose_dist(get_actual_tcp_pose(), goal))\n')
    assert float(core.robot.log[0]) == pytest.approx(0.0, abs=1e-6)


def test_a_bad_servoc_target_stops_the_program_naming_servoc(cell):
    core, dt = cell
    messages = run(core, dt, 'servoc([0.1, 0.2, 0.3, 0, 0], a=1.2, v=0.25)\n')
    assert len(errors(messages)) == 1 and 'Error: servoc must be a list of 6' in errors(messages)[0], errors(messages)


def test_the_safety_limits_are_the_joint_limits_and_the_arms_reach(cell):
    core, dt = cell
    lower, upper = core.arm.lower, core.arm.upper
    run(core, dt, 'textmsg(is_within_safety_limits(get_actual_joint_positions()))\n'
                  'textmsg(is_within_safety_limits([%r, 0, 0, 0, 0, 0]))\n'
                  'textmsg(is_within_safety_limits([0, 0, 0, 0, 0, %r]))\n'
                  'textmsg(is_within_safety_limits(get_actual_tcp_pose()))\n'
                  'textmsg(is_within_safety_limits(p[3, 0, 0, 0, 3.14, 0]))\n'
                  % (float(upper[0]) + 0.01, float(lower[5]) - 0.01))
    assert list(core.robot.log)[:5] == ['True', 'False', 'False', 'True', 'False']


def test_the_target_payload_is_what_set_payload_gave(cell):
    core, dt = cell
    run(core, dt, 'set_payload(1.5, [0, 0.01, 0.05])\n'
                  'textmsg(get_target_payload())\ntextmsg(get_target_payload_cog())\n')
    assert list(core.robot.log)[:2] == ['1.5', '[0, 0.01, 0.05]']


def test_protective_stop_pauses_the_program_where_it_called_it_until_unlocked_and_played(cell):
    core, dt = cell
    core.script_command('protective_stop()\ntextmsg("after")\n')
    for _ in range(int(round(5.5 / dt))):  # the robot unlocks a protective stop after 5 s
        core.step(dt)
    assert core.robot.safety_mode == rs.PROTECTIVE_STOP and core.robot.program_state == rs.PAUSED
    assert 'after' not in core.robot.log
    assert core.dashboard('unlock protective stop') == 'Protective stop releasing'
    assert core.dashboard('play') == 'Starting program'
    for _ in range(5):
        core.step(dt)
    assert list(core.robot.log)[-1] == 'after' and not core.script_running


WATCHED = 'rtde_set_watchdog("input_int_register_0", 10, "%s")\nwhile True:\n  sync()\nend\n'


@pytest.fixture(params=UR_TYPES)
def faced(request, configured_model):
    """A core with its network faces, and an RTDE client that writes input_int_register_0 (ur_rtde's command
    register, which its watchdog watches)."""
    cell = Cell(configured_model, request.param)
    client = cell.client()
    recipe = client.setup_inputs(['input_int_register_0'])
    yield cell, client, recipe
    client.close()
    cell.faces.shutdown()


def write(client, recipe, value):
    client.write(recipe, {'input_int_register_0': value})
    client.controller_version()  # a reply after the data package: the package has been taken


@pytest.mark.parametrize('action, state', [('pause', rs.PAUSED), ('stop', rs.STOPPED)])
def test_an_rtde_watchdog_acts_one_period_after_the_clients_last_write(faced, action, state):
    cell, client, recipe = faced
    core = cell.core
    with cell.lock:
        core.script_command(WATCHED % action)
    for cycle in range(int(round(0.5 / cell.dt))):
        write(client, recipe, cycle)
        cell.step()
    last_write = core.uptime - cell.dt
    assert core.robot.program_state == rs.PLAYING
    while core.robot.program_state == rs.PLAYING:
        cell.step()
        assert core.uptime < last_write + 1.0, 'the watchdog did not act within a second'
    # It acts in the first cycle more than its period (0.1 s) after the write.
    assert core.uptime - last_write == pytest.approx(0.1 + cell.dt, abs=cell.dt + 1e-9)
    assert core.robot.program_state == state
    assert any('RTDE input watchdog: input_int_register_0 was not written for 0.1 s' in line
               for line in core.robot.log)


def test_an_ignoring_watchdog_lets_the_program_run(faced):
    cell, _, _ = faced
    with cell.lock:
        cell.core.script_command(WATCHED % 'ignore')
    cell.step(int(round(0.5 / cell.dt)))
    assert cell.core.robot.program_state == rs.PLAYING


def test_a_watchdog_on_a_field_rtde_does_not_take_stops_the_program_naming_it(faced):
    cell, _, _ = faced
    with cell.lock:
        cell.core.script_command('rtde_set_watchdog("output_int_register_0", 10)\n')
    cell.step(2)
    assert list(cell.core.robot.log)[-1] == (
        'RuntimeException: Runtime error in line 1, column 1 Error: rtde_set_watchdog: output_int_register_0 '
        'is not an RTDE input of this controller')


@pytest.mark.parametrize('call, error', [
    ('rtde_set_watchdog("input_int_register_0", 0)', 'rtde_set_watchdog: min_frequency must be a number above 0 Hz, '
                                                     'not 0'),
    ('rtde_set_watchdog("input_int_register_0", 10, "halt")',
     'rtde_set_watchdog: action must be "ignore", "pause" or "stop", not halt'),
    ('enable_external_ft_sensor(True)', "enable_external_ft_sensor: the simulated robot measures its own TCP wrench "
                                        "and takes no external F/T sensor's readings"),
])
def test_a_bad_watchdog_or_an_external_sensor_stops_the_program_naming_it(cell, call, error):
    core, dt = cell
    messages = run(core, dt, 'enable_external_ft_sensor(False)\n%s\n' % call)
    assert errors(messages) == ['script_command: RuntimeException: Runtime error in line 2, column 1 Error: %s; '
                                'program stopped' % error]


def test_without_contact_the_tool_meets_nothing_and_the_joints_feel_no_external_torque(cell):
    core, dt = cell
    # The kinematic arm touches nothing: no contact, and no torque beyond moving itself.
    run(core, dt, 'textmsg(tool_contact(direction=[0, 0, -1, 0, 0, 0]))\ntextmsg(get_joint_torques())\n')
    assert list(core.robot.log)[:2] == ['0', '[0, 0, 0, 0, 0, 0]']


def test_zero_ftsensor_runs_on_both_generations_and_the_dashboard_names_the_robot(cell):
    core, dt = cell
    assert errors(run(core, dt, 'zero_ftsensor()\n')) == []
    serial = core.dashboard('get serial number')
    assert serial.isdigit() and serial.startswith('2000')
    assert core.dashboard('get robot model') == {'ur3': 'UR3', 'ur5e': 'UR5'}[core.software.ur_type]

