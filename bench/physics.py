#!/usr/bin/env python3
"""The physics cell (MuJoCo) alone, no ROS: steps per second, its cost beside bare mj_step, a held object.

    python3 bench/physics.py [--seconds 20] [--runs 5] [--output bench/RESULTS.md]

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

Then the cell's own cost beside MuJoCo's, for ur3 (a CB3: step() of 8 ms, four
timesteps a call) and ur5e (an e-Series: step() of 2 ms, one timestep), each
with the box held as above, holding still and moving along a sine: the cell
is driven through its own interface (set_arm_reference, step), its
references computed beforehand, and measured in chunks of half a second of
simulated time. After each chunk, from a copy of the state the chunk started
from (MjData, the same MjModel), two bare loops of mujoco.mj_step, one
timestep a call, for as many timesteps:
- ctrl held: the controls as the chunk found them, never changed;
- along the path: before each timestep, the position servos' reference
  the cell gives them there (interpolated over a cycle's timesteps as the
  cell does, without its inertia feedforward) written into ctrl, and each
  cycle's velocity, so that the arm moves as in the cell (ctrl held, a
  moving arm comes to rest within milliseconds, and MuJoCo then has less
  to do).
The ratio is bare CPU time over the cell's: 1.0 when the cell adds nothing
to MuJoCo. Interleaving the chunks shares the machine's ups and downs among
the three; each run gives one ratio over all its chunks, and the table shows
the median of `runs` runs and their range.
Figures, not pass/fail: exit status 0 when every measurement ran.
"""
import argparse
import copy
import math
import os
import sys
import tempfile
import time

import numpy as np

import benchlib  # this folder is the script's, first on sys.path

START = np.array([0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0])
ARM_JOINTS = ('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
              'wrist_3_joint')
BOX = """
  - name: held
    shape: box
    size: [0.06, 0.05, 0.12]
    pose: [%s, 0.06]
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


def build(folder, ur_type='ur3'):
    import mujoco
    from ur3_ft_gripper_description import kinematics
    from ur3_ft_gripper_description.devices.physics.cell import Cell
    from ur3_ft_gripper_description.devices.physics.world import load_world
    from ur3_ft_gripper_description.model import description, export, mjcf
    from ur3_ft_gripper_description.number_text import number_list

    mappings = export.model_mappings(ur_type=ur_type)
    doc = description.expand_model(mappings)
    urdf = description.to_xml(doc)
    model = kinematics.Model(urdf)
    start = start_pose(ur_type, urdf)
    tcp = model.transform(model.root(), 'gripper_tcp', dict(zip(ARM_JOINTS, start)))[:3, 3]
    with open(os.path.join(description.package_path('ur3_ft_gripper_description'), 'config', 'worlds',
                           'default.yaml')) as f:
        world_text = f.read() + BOX % number_list(tcp[:2])
    world_path = os.path.join(folder, 'world.yaml')
    with open(world_path, 'w') as f:
        f.write(world_text)
    path = os.path.join(folder, 'robot.xml')
    mjcf.write_mjcf(doc, mappings, path)
    return Cell(path, urdf, load_world(world_path), initial_arm=start), mujoco.__version__


def start_pose(ur_type, urdf):
    """START for the UR3; for another model, the joints that put its tool0 where the UR3's is at START."""
    if ur_type == 'ur3':
        return START
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics
    from ur3_ft_gripper_description.model import description, export
    ur3 = description.to_xml(description.expand_model(export.model_mappings(ur_type='ur3')))
    tool = ArmKinematics(ur3, ARM_JOINTS, 'base', 'tool0').forward(START)
    return ArmKinematics(urdf, ARM_JOINTS, 'base', 'tool0').inverse(tool, START, tolerance=1e-10)


def held_up(ur_type='ur3'):
    """(cell, its joint motion, MuJoCo's version): the box between the pads, gripped with 125 N, lifted 15 cm."""
    from ur3_ft_gripper_description.devices.ur_arm.physics_joints import PhysicsJointMotion
    from ur3_ft_gripper_description.devices.ur_arm.joints import JointCommand
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics

    with tempfile.TemporaryDirectory() as folder:
        cell, version = build(folder, ur_type)
    motion = PhysicsJointMotion(cell)
    kin = ArmKinematics(cell.urdf_text, cell.arm_joints, 'base', 'tool0')
    cell.command_finger(0.0, 0.15, 125.0)
    cell.step(1.5)
    say('%s fingers: %s at %.1f mm' % (ur_type, cell.finger().motion, cell.finger().opening * 1e3))
    seed, start = motion.reference.copy(), kin.forward(motion.reference)
    for k in range(1, 751):  # lift 15 cm in 1.5 s along a line
        target = start.copy()
        target[2, 3] += 0.15 * (0.5 - 0.5 * math.cos(math.pi * k / 750.0))
        seed = kin.inverse(target, seed, tolerance=1e-10)
        motion.step(JointCommand('MOVE', seed), 0.002)
    return cell, motion, version


def bench(seconds):
    from ur3_ft_gripper_description.devices.ur_arm.joints import JointCommand

    cell, motion, version = held_up()
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


# The two control cycles: a CB3's (125 Hz) and an e-Series' (500 Hz), each model with its own.
CYCLES = (('ur3', 0.008), ('ur5e', 0.002))
CHUNK = 0.5  # s of simulated time per measured chunk


def _slice(ids):
    ids = list(ids)
    return slice(ids[0], ids[-1] + 1) if ids == list(range(ids[0], ids[-1] + 1)) else np.array(ids)


def beside_bare(seconds, runs):
    """{ur_type: {'per_call': timesteps per step(), phase: [(timesteps, cell CPU s, bare CPU s with ctrl held,
    bare CPU s along the path), one per run]}}."""
    import mujoco
    from ur3_ft_gripper_description.model import mjcf

    results = {}
    for ur_type, period in CYCLES:
        cell, _, _ = held_up(ur_type)
        model = cell.model
        position_ctrl = _slice(model.actuator(name).id for name in cell.arm_joints)
        velocity_ctrl = _slice(model.actuator(name + mjcf.VELOCITY_SUFFIX).id for name in cell.arm_joints)
        per_call = int(round(period / cell.timestep))
        calls = int(round(CHUNK / period))
        results[ur_type] = {'per_call': per_call}
        centre, gripped, opening = cell.arm_position, in_gripper(cell), cell.finger().opening
        # Half the streamed sine's swing above: over the 100 s of five runs the box then slips ~8 mm in the
        # grasp (a full swing: 20 mm, and it works loose).
        amplitude, frequency = np.array([0.15, 0.1, -0.15, 0.25, 0.25, 0.4]), 0.5
        clock = [0]  # control cycles since the moving phase began: its sine goes on from chunk to chunk
        last = [centre]  # the reference the cell ended the last chunk at

        def servo_path(references):
            """[(velocity, [position servos' reference at each timestep]), one per cycle], as the cell has them."""
            path, previous = [], last[0]
            for position, velocity in references:
                path.append((velocity, [previous + (position - previous) * (float(k) / per_call)
                                        for k in range(per_call)]))
                previous = position
            last[0] = previous
            return path

        def holding():
            still = np.zeros(len(centre))
            return [(centre, still)] * calls

        def moving():
            # Out from the held pose and back, 0.5 Hz: from rest, without a jump of the reference's velocity.
            references = []
            for _ in range(calls):
                clock[0] += 1
                phase = 2.0 * math.pi * frequency * clock[0] * period
                references.append((centre + amplitude * (0.5 - 0.5 * math.cos(phase)),
                                   amplitude * math.pi * frequency * math.sin(phase)))
            return references

        for phase, references_of in (('holding', holding), ('moving', moving)):
            measured = []
            for _ in range(runs):
                timesteps, cell_cpu, held_cpu, path_cpu = 0, 0.0, 0.0, 0.0
                for _ in range(int(round(seconds / CHUNK))):
                    references = references_of()
                    path = servo_path(references)
                    start = copy.copy(cell.data)
                    begin = time.process_time()
                    for position, velocity in references:
                        cell.set_arm_reference(position, velocity)
                        cell.step(period)
                    cell_cpu += time.process_time() - begin
                    timesteps += calls * per_call
                    data = copy.copy(start)
                    begin = time.process_time()
                    for _ in range(calls * per_call):
                        mujoco.mj_step(model, data)
                    held_cpu += time.process_time() - begin
                    data = copy.copy(start)
                    ctrl = data.ctrl
                    begin = time.process_time()
                    for velocity, positions in path:
                        ctrl[velocity_ctrl] = velocity
                        for position in positions:
                            ctrl[position_ctrl] = position
                            mujoco.mj_step(model, data)
                    path_cpu += time.process_time() - begin
                measured.append((timesteps, cell_cpu, held_cpu, path_cpu))
            results[ur_type][phase] = measured
            say('%s %s: cell / bare, ctrl held: %s; along the path: %s' % (
                ur_type, phase, ' '.join('%.3f' % (held / ours) for _, ours, held, _ in measured),
                ' '.join('%.3f' % (path / ours) for _, ours, _, path in measured)))
        # Still held: the pads on the box, no protective stop; its slip over the motion (m) is said.
        shift = float(np.linalg.norm(in_gripper(cell) - gripped))
        say('%s: the box %.1f mm from where it was gripped' % (ur_type, shift * 1e3))
        results[ur_type]['shift'] = shift
        if cell.protective_stop is not None or abs(cell.finger().opening - opening) > 0.002 or shift > 0.02:
            raise RuntimeError('%s: the box was not held all along' % ur_type)
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


def ratio_section(ratios, seconds, runs):
    def figures(pairs):
        values = sorted(bare / ours for ours, bare in pairs)
        return '**%.2f** (%.2f-%.2f)' % (benchlib.median(values), values[0], values[-1])
    lines = [
        'The cell beside bare `mujoco.mj_step` (one timestep a call), the box held as above, the cell driven '
        'through its own interface (set_arm_reference, step) with references computed beforehand, moving: '
        'out and back along a 0.5 Hz sine of half the swing above (the box slipped %s in the grasp over all '
        'the runs, still held); %g s of simulated time per run in chunks of %g s, each chunk followed by the two '
        'bare loops from a copy of its starting state. Bare CPU time over the cell\'s, median of %d runs '
        '(their range); goal >= 0.9.' % (
            ', '.join('%.1f mm (%s)' % (ratios[ur_type]['shift'] * 1e3, ur_type) for ur_type, _ in CYCLES),
            seconds, CHUNK, runs),
        '',
        '| ur_type | step() | phase | cell us per timestep | cell / bare, ctrl held | cell / bare, along the path |',
        '| --- | --- | --- | ---: | ---: | ---: |',
    ]
    for ur_type, period in CYCLES:
        for phase in ('holding', 'moving'):
            measured = ratios[ur_type][phase]
            lines.append('| %s | %g ms, %d timestep%s | %s | %.1f | %s | %s |' % (
                ur_type, period * 1e3, ratios[ur_type]['per_call'], 's' if ratios[ur_type]['per_call'] > 1 else '',
                phase, benchlib.median([ours / timesteps for timesteps, ours, _, _ in measured]) * 1e6,
                figures([(ours, held) for _, ours, held, _ in measured]),
                figures([(ours, path) for _, ours, _, path in measured])))
    return '\n'.join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=20.0, help='simulated seconds per measurement')
    parser.add_argument('--runs', type=int, default=5, help='runs of the comparison with bare mj_step')
    parser.add_argument('--output', help='RESULTS.md to write the section "physics" into')
    args = parser.parse_args(argv)
    from ur3_ft_gripper_description.devices.physics import MissingMuJoCo
    load = benchlib.load_average()
    try:
        results = bench(args.seconds)
        ratios = beside_bare(args.seconds, args.runs)
    except MissingMuJoCo as exc:
        print('physics bench: %s' % exc, file=sys.stderr)
        return 1
    text = section(results, load) + '\n\n' + ratio_section(ratios, args.seconds, args.runs)
    print(text)
    if args.output:
        benchlib.replace_section(args.output, 'physics', text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
