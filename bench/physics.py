#!/usr/bin/env python3
"""The physics cell (MuJoCo) alone, no ROS: steps per second, and how a held object fares.

    python3 bench/physics.py [--seconds 20] [--output bench/RESULTS.md]

In the sourced workspace (tools/quickstart shell), with MuJoCo installed. The
default model (UR3 + FT 300 + 2F-140) in the default world plus a 1 kg box
between the pads; the fingers close on the box with 125 N and the arm lifts it
15 cm. Then, one after the other, each for `seconds` of simulated time:
- holding still: the arm in HOLD through the joint-motion interface, and the
  box's creep in the grasp;
- moving: joints streamed at 500 Hz (SERVO) along a 0.5 Hz sine of 0.3 to
  0.8 rad, the box held;
- every joint at its velocity limit there and back (MOVE, a quintic whose
  peak speed is the fastest joint's limit): the box's slip in the grasp.
Steps per second are CPU time of this process (one core: MuJoCo steps on
one thread), and the real-time factor is simulated over CPU seconds.
Figures, not pass/fail: exit status 0 when every measurement ran.
"""
import argparse
import math
import os
import sys
import tempfile
import time

import numpy as np

import benchlib  # this folder is the script's, first on sys.path

START = np.array([0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0])
BOX = """
  - name: held
    shape: box
    size: [0.06, 0.05, 0.12]
    pose: [%r, %r, 0.06]
    mass: 1.0
    friction: 0.5
"""


def say(text):
    print('[physics bench] %s' % text, file=sys.stderr)


def in_gripper(cell):
    base, rotation = cell.body_pose(cell.gripper_base)
    return rotation.T.dot(cell.object_pose('held')[0] - base)


def timed(cell, run):
    """(steps per CPU second, real-time factor) of run(), which steps `cell`."""
    start_time, start_cpu = cell.time, time.process_time()
    run()
    cpu = time.process_time() - start_cpu
    simulated = cell.time - start_time
    return simulated / cell.timestep / cpu, simulated / cpu


def build(folder):
    import mujoco
    from ur3_ft_gripper_description import kinematics
    from ur3_ft_gripper_description.devices.physics.cell import Cell
    from ur3_ft_gripper_description.devices.physics.world import load_world
    from ur3_ft_gripper_description.model import description, export, mjcf

    mappings = export.model_mappings()
    doc = description.expand_model(mappings)
    urdf = description.to_xml(doc)
    model = kinematics.Model(urdf)
    tcp = model.transform(model.root(), 'gripper_tcp', dict(zip(
        ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
         'wrist_3_joint'], START)))[:3, 3]
    with open(os.path.join(description.package_path('ur3_ft_gripper_description'), 'config', 'worlds',
                           'default.yaml')) as f:
        world_text = f.read() + BOX % (tcp[0], tcp[1])
    world_path = os.path.join(folder, 'world.yaml')
    with open(world_path, 'w') as f:
        f.write(world_text)
    path = os.path.join(folder, 'robot.xml')
    mjcf.write_mjcf(doc, mappings, path)
    return Cell(path, urdf, load_world(world_path), initial_arm=START), mujoco.__version__


def bench(seconds):
    from ur3_ft_gripper_description.devices.ur_arm.physics_joints import PhysicsJointMotion
    from ur3_ft_gripper_description.devices.ur_arm.joints import JointCommand
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics

    with tempfile.TemporaryDirectory() as folder:
        cell, version = build(folder)
    motion = PhysicsJointMotion(cell)
    kin = ArmKinematics(cell.urdf_text, cell.arm_joints, 'base', 'tool0')
    cell.command_finger(0.0, 0.15, 125.0)
    cell.step(1.5)
    say('fingers: %s at %.1f mm' % (cell.finger().motion, cell.finger().opening * 1e3))
    seed, start = motion.reference.copy(), kin.forward(motion.reference)
    for k in range(1, 751):  # lift 15 cm in 1.5 s along a line
        target = start.copy()
        target[2, 3] += 0.15 * (0.5 - 0.5 * math.cos(math.pi * k / 750.0))
        seed = kin.inverse(target, seed, tolerance=1e-10)
        motion.step(JointCommand('MOVE', seed), 0.002)
    steps = int(round(seconds / 0.002))
    results = {'mujoco': version, 'seconds': seconds}

    def hold():
        for _ in range(steps):
            motion.step(JointCommand('HOLD'), 0.002)
    before = in_gripper(cell)
    results['hold'] = timed(cell, hold)
    results['creep'] = float(np.linalg.norm(in_gripper(cell) - before)) / seconds

    amplitude = np.array([0.3, 0.2, -0.3, 0.5, 0.5, 0.8])
    centre = motion.reference.copy()

    def stream():
        for k in range(steps):
            phase = 2.0 * math.pi * 0.5 * (k + 1) * 0.002
            motion.step(JointCommand('SERVO', centre + amplitude * math.sin(phase)), 0.002)
    results['servo'] = timed(cell, stream)
    for _ in range(500):
        motion.step(JointCommand('MOVE', centre), 0.002)

    delta = np.array([1.5, 0.4, -0.6, 1.0, 0.0, 3.0])
    duration = float(np.max(1.875 * np.abs(delta) / cell.arm_velocity_limits))
    before, worst = in_gripper(cell), [0.0]

    def full_speed():
        for sign in (1.0, -1.0):
            origin = motion.reference.copy()
            count = int(round(duration / 0.002))
            for k in range(1, count + 1):
                s = k / float(count)
                blend = 10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5
                rate = (30 * s ** 2 - 60 * s ** 3 + 30 * s ** 4) / duration
                motion.step(JointCommand('MOVE', origin + sign * delta * blend, sign * delta * rate), 0.002)
                if k % 25 == 0:  # every 50 ms: measuring at every step would weigh on the timing
                    worst[0] = max(worst[0], float(np.linalg.norm(in_gripper(cell) - before)))
        for _ in range(250):
            motion.step(JointCommand('HOLD'), 0.002)
    results['full_speed'] = timed(cell, full_speed)
    results['slip'] = float(np.linalg.norm(in_gripper(cell) - before))
    results['slip_worst'] = worst[0]
    results['held'] = cell.finger().motion == 'on_object' and cell.protective_stop is None
    results['contacts'] = int(cell.data.ncon)
    return results


def section(results, load):
    hold, servo, fast = results['hold'], results['servo'], results['full_speed']
    rows = [('holding still (HOLD)', hold), ('streaming a sine (SERVO, 500 Hz)', servo),
            ('every joint at its velocity limit (MOVE)', fast)]
    lines = [
        '### Physics cell (MuJoCo %s, no ROS), %s' % (results['mujoco'], benchlib.now_text()),
        '',
        'Machine: %s; load average before: %s.' % (benchlib.machine(), load),
        '',
        'UR3 + FT 300 + 2F-140 in config/worlds/default.yaml, holding a 1 kg box with 125 N, 15 cm up; '
        '2 ms steps through the joint-motion interface; %g s of simulated time each (the fast move: '
        'its own length); %d contacts at the end. Goal: 10x real time on one core (5000 steps/s).'
        % (results['seconds'], results['contacts']),
        '',
        '| | steps per CPU second | real-time factor |',
        '| --- | --- | --- |',
    ]
    lines += ['| %s | %.0f | %.1f |' % (name, rate, factor) for name, (rate, factor) in rows]
    lines += [
        '',
        'The held box, in the 2F-140\'s frame: creep while holding still %.3f um/s (limit 17); slip over the '
        'full-speed move there and back %.2f mm (largest on the way %.2f mm); %s.' % (
            results['creep'] * 1e6, results['slip'] * 1e3, results['slip_worst'] * 1e3,
            'still held, no protective stop' if results['held'] else 'NOT HELD'),
    ]
    return '\n'.join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=20.0, help='simulated seconds per measurement')
    parser.add_argument('--output', help='RESULTS.md to write the section "physics" into')
    args = parser.parse_args(argv)
    from ur3_ft_gripper_description.devices.physics import MissingMuJoCo
    load = benchlib.load_average()
    try:
        results = bench(args.seconds)
    except MissingMuJoCo as exc:
        print('physics bench: %s' % exc, file=sys.stderr)
        return 1
    text = section(results, load)
    print(text)
    if args.output:
        benchlib.replace_section(args.output, 'physics', text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
