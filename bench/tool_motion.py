#!/usr/bin/env python3
"""URScript's motions (devices/ur_arm/tool_motion.py) alone, no ROS: the cost of one control cycle.

    python3 bench/tool_motion.py [--runs 5] [--output bench/RESULTS.md]

In the sourced workspace (tools/quickstart shell). For ur3 (a CB3: 8 ms
cycles) and ur5e (an e-Series: 2 ms), on the bare arm's expanded model, with
a 0.2 m TCP offset, each motion stepped to its end (speedl: for a second)
with the commanded joints fed back as the actual ones:
- movel over the unit tests' move (0.17 m on ur3, 0.29 m on ur5e, turning
  0.2 rad), at the manual's a and v;
- two movel blended with r = 0.02 at a right-angle corner;
- speedl at 0.08 m/s, a = 0.5.
Per motion: its construction (movel checks its whole path then), and step()
per cycle: median, 99th percentile and largest, and the median as a share of
the control period (the cycle has the rest for everything else). Each runs
`runs` times; the figures are over all runs' cycles, CPU time of this process.
Figures, not pass/fail: exit status 0 when every measurement ran.
"""
import argparse
import time

import numpy as np

import benchlib  # this folder is the script's, first on sys.path

JOINTS = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
          'wrist_3_joint']
PERIOD = {'ur3': 0.008, 'ur5e': 0.002}
START = np.array([0.3, -1.4, 1.6, -1.8, -1.57, 0.2])
MOVE = {'ur3': np.array([0.12, 0.06, -0.08]), 'ur5e': np.array([0.25, 0.1, -0.12])}


def cases(arm, ur_type):
    """{name: build()} of the motions measured; build() gives (motion, then) with `then` the blend's second
    move's builder or None."""
    from ur3_ft_gripper_description.devices.ur_arm import tool_motion as tm
    from ur3_ft_gripper_description.devices.ur_arm.cartesian import pose_from_ur_pose
    tcp = np.eye(4)
    tcp[2, 3] = 0.2
    start = tm.tcp_pose(arm, tcp, START)
    target = start.copy()
    target[:3, 3] += MOVE[ur_type]
    target = target.dot(pose_from_ur_pose([0, 0, 0, 0.2 / np.sqrt(2), 0.2 / np.sqrt(2), 0]))
    corner, end = start.copy(), start.copy()
    corner[:3, 3] += [0.1, 0.0, 0.0]
    end[:3, 3] += [0.1, 0.1, 0.0]
    return {
        'movel': lambda: (tm.LinearMove(arm, tcp, START, None, target), None),
        'movel, movel (r=0.02)': lambda: (tm.LinearMove(arm, tcp, START, None, corner, r=0.02),
                                          lambda m: tm.LinearMove(arm, tcp, None, None, end, previous=m)),
        'speedl (1 s)': lambda: (tm.ToolSpeed(arm, tcp, START, None, [0.08, 0, 0, 0, 0, 0], 0.5), None),
    }


def measure(build, dt):
    """(construction seconds, [step seconds]) of one run of a motion."""
    started = time.process_time()
    motion, then = build()
    built = time.process_time() - started
    steps, q = [], START
    for _ in range(int(round(1.0 / dt)) if motion.name == 'speedl' else 100000):
        if motion.done:
            break
        if then is not None and motion.returned:
            started = time.process_time()
            motion, then = then(motion), None
            built += time.process_time() - started
        started = time.process_time()
        q = motion.step(dt, q, None)
        steps.append(time.process_time() - started)
    return built, steps


def bench(runs):
    from ur3_ft_gripper_testing.model import configured
    from ur3_ft_gripper_description.devices.ur_arm.arm_kinematics import ArmKinematics
    results = []
    for ur_type in ('ur3', 'ur5e'):
        arm = ArmKinematics(configured(ur_type, False, False).text, JOINTS)
        for name, build in cases(arm, ur_type).items():
            built, steps = [], []
            for _ in range(runs):
                b, s = measure(build, PERIOD[ur_type])
                built.append(b)
                steps.extend(s)
            results.append((ur_type, name, len(steps) // runs, benchlib.median(built), steps))
    return results


def section(results, runs, load):
    lines = [
        '## URScript motions per control cycle (`python3 bench/tool_motion.py`)',
        '',
        '### tool_motion.py, no ROS, %s' % benchlib.now_text(),
        '',
        'Machine: %s; load average before: %s. %d runs each; CPU time of this process.' % (
            benchlib.machine(), load, runs),
        '',
        '| ur_type (period) | motion | cycles | construction (ms) | step median (ms) | p99 (ms) | max (ms) '
        '| median / period |',
        '| --- | --- | --- | --- | --- | --- | --- | --- |',
    ]
    for ur_type, name, cycles, built, steps in results:
        period = PERIOD[ur_type]
        median = benchlib.median(steps)
        lines.append('| %s (%g ms) | %s | %d | %.1f | %.3f | %.3f | %.3f | %.0f %% |' % (
            ur_type, period * 1e3, name, cycles, built * 1e3, median * 1e3, benchlib.percentile(steps, 99) * 1e3,
            max(steps) * 1e3, 100.0 * median / period))
    return '\n'.join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--runs', type=int, default=5, help='runs of each motion')
    parser.add_argument('--output', help='RESULTS.md to write the section "tool_motion" into')
    args = parser.parse_args(argv)
    load = benchlib.load_average()
    text = section(bench(args.runs), args.runs, load)
    print(text)
    if args.output:
        benchlib.replace_section(args.output, 'tool_motion', text)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
