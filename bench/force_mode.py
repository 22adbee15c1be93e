#!/usr/bin/env python3
"""force_mode on the physics cell, no ROS: the arm's control cycle while it presses, beside the same arm holding.

    python3 bench/force_mode.py [--seconds 2] [--runs 5] [--output bench/RESULTS.md]

In the sourced workspace (tools/quickstart shell), with MuJoCo installed. The
arm's core (ArmCore) on the physics cell of the default model in the default
world, at examples/force_mode_press.py's start pose, at each generation's
period (ur3 settings: 8 ms; the same cell at 2 ms, as an e-Series runs it):
- holding: External Control idle, no program;
- pressing: the example's program, force_mode along the tool's z at 20 N,
  measured once the press has settled on the table: each cycle steps the
  admittance against the servos' damping at the TCP (a Jacobian, its
  inverse), cancels the servos' cross pull (force_mode.uncoupled: their
  stiffness in the force frame, one small solve) and solves the displaced
  pose's inverse kinematics to under a nanometre.
CPU time of this process per control cycle (ArmCore.step, MuJoCo's timesteps
included), in chunks of `seconds` of simulated time, the two cases
interleaved; the table shows the median over `runs` runs and the ratio.
Figures, not pass/fail: exit status 0 when every measurement ran.
"""
import argparse
import os
import sys
import tempfile
import time
import types

import benchlib  # this folder is the script's, first on sys.path

FORCE = 20.0
SETTLE = 3.0  # s of simulated time for the press to land and settle before it is measured
PERIODS = (('8 ms (CB3)', 125.0), ('2 ms (e-Series)', 500.0))


def say(text):
    print('[force_mode bench] %s' % text, file=sys.stderr)


def new_press(loop_hz):
    """(core, dt, the example's program text) on a fresh cell at the example's start pose."""
    import rospkg
    from ur3_ft_gripper_description import clients
    from ur3_ft_gripper_description.devices.physics.cell import Cell
    from ur3_ft_gripper_description.devices.physics.world import load_world
    from ur3_ft_gripper_description.devices.ur_arm import core as arm_core
    from ur3_ft_gripper_description.devices.ur_arm.physics_joints import PhysicsJointMotion
    from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings
    from ur3_ft_gripper_description.model import description, export, mjcf
    from ur3_ft_gripper_testing import shipped
    force_mode_press = shipped.script('examples/force_mode_press.py')

    mappings = export.model_mappings()
    doc = description.expand_model(mappings)
    urdf = description.to_xml(doc)
    tool = clients.ToolKinematics(types.SimpleNamespace(get_param=lambda name: urdf))
    x, y = force_mode_press.START_XY
    start = tool.path_to([0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0], x, y, force_mode_press.START_HEIGHT,
                         force_mode_press.CLEAR_HEIGHT)[-1]
    config = os.path.join(rospkg.RosPack().get_path('ur_robot_driver'), 'config', 'ur3_controllers.yaml')
    values = {'~ur_type': 'ur3', '~controller_config_file': config, 'robot_description': urdf,
              '~controllers': 'joint_state_controller scaled_pos_joint_traj_controller',
              '~initial_positions': [float(q) for q in start], '~loop_hz': loop_hz}
    settings = read_settings(lambda name, default=None: values.get(name, default))
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, 'robot.xml')
        mjcf.write_mjcf(doc, mappings, path)
        world = load_world(os.path.join(benchlib.PACKAGE_DIR, 'config', 'worlds', 'default.yaml'))
        cell = Cell(path, urdf, world, initial_arm=settings.initial)
    core = arm_core.ArmCore(settings, PhysicsJointMotion.from_settings(cell, settings))
    return core, 1.0 / loop_hz, force_mode_press.PROGRAM.format(force=FORCE, speed=0.05, seconds=10000)


def per_cycle(core, dt, seconds):
    """CPU seconds per control cycle over `seconds` of simulated time."""
    cycles = int(round(seconds / dt))
    began = time.process_time()
    for _ in range(cycles):
        core.step(dt)
    return (time.process_time() - began) / cycles


def bench(seconds, runs):
    results = []
    for label, loop_hz in PERIODS:
        holding, dt, _ = new_press(loop_hz)
        pressing, _, program = new_press(loop_hz)
        per_cycle(holding, dt, 1.0)
        per_cycle(pressing, dt, 1.0)
        pressing.script_command(program)
        per_cycle(pressing, dt, SETTLE)
        if not pressing.script_running:
            raise RuntimeError('the press stopped: %s' % pressing.take_messages())
        held, pressed = [], []
        for _ in range(runs):
            held.append(per_cycle(holding, dt, seconds))
            pressed.append(per_cycle(pressing, dt, seconds))
        force = -pressing.tcp_force()[1][2]
        say('%s: holding %.0f us, pressing %.0f us a cycle; the press reads %.1f N'
            % (label, 1e6 * benchlib.median(held), 1e6 * benchlib.median(pressed), force))
        results.append((label, held, pressed, force))
    return results


def section(results, seconds, runs, load):
    lines = [
        '### force_mode on physics (`bench/force_mode.py`, no ROS), %s' % benchlib.now_text(),
        '',
        'Machine: %s; load average before: %s. ArmCore.step on the physics cell at the example\'s start '
        'pose: holding (no program) and pressing (the example\'s force_mode at %g N, settled on the '
        'table); CPU time per control cycle, MuJoCo included; %d runs of %g s of simulated time each, '
        'interleaved; median (range).' % (benchlib.machine(), load, FORCE, runs, seconds),
        '',
        '| period | holding (us a cycle) | pressing (us a cycle) | pressing / holding | the robot reads (N) |',
        '| --- | --- | --- | --- | --- |',
    ]
    for label, held, pressed, force in results:
        lines.append('| %s | %.0f (%.0f-%.0f) | %.0f (%.0f-%.0f) | %.2f | %.1f |' % (
            label, 1e6 * benchlib.median(held), 1e6 * min(held), 1e6 * max(held), 1e6 * benchlib.median(pressed),
            1e6 * min(pressed), 1e6 * max(pressed), benchlib.median(pressed) / benchlib.median(held), force))
    return '\n'.join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=2.0, help='simulated seconds per chunk')
    parser.add_argument('--runs', type=int, default=5, help='chunks of each case')
    parser.add_argument('--output', help='RESULTS.md to write the section "force_mode" into')
    args = parser.parse_args(argv)
    from ur3_ft_gripper_description.devices.physics import MissingMuJoCo
    load = benchlib.load_average()
    try:
        results = bench(args.seconds, args.runs)
    except MissingMuJoCo as exc:
        print('force_mode bench: %s' % exc, file=sys.stderr)
        return 1
    text = section(results, args.seconds, args.runs, load)
    print(text)
    if args.output:
        benchlib.replace_section(args.output, 'force_mode', text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
