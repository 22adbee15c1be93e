#!/usr/bin/env python3
"""URScript's cost, no ROS: compiling programs, and the interpreter's share of a control cycle.

    python3 bench/urscript.py [--runs 5] [--seconds 1] [--output bench/RESULTS.md]

In the sourced workspace (tools/quickstart shell). Two measurements, CPU
time of this process:
- compile: urscript.compile_script (lark's LALR parse and the compiler, as
  script_command runs it) of each program in test/data/urscript/*.script,
  read when this runs, and of a generated program of 2000 lines of pose
  math and movel; median and 99th percentile over `runs` x 20 compiles (the
  generated one: `runs` x 2). A program the robot refuses is timed up to its
  CompileError. The first compile in a process also builds the parser: its
  own row.
- per control cycle: ArmCore.step(dt) of the arm's core as the node builds
  it (settings.read_settings over ur_robot_driver's <ur_type>_controllers.yaml
  and the bare arm's expanded model, sim_arm.launch's controllers, the
  kinematic joints), for ur3 (a CB3: 8 ms cycles) and ur5e (an e-Series:
  2 ms), with (a) External Control idle, no program; (b) a force_mode
  program whose watchdog thread checks the TCP's force and travel every
  cycle while main waits on sync(); (c) a tight computing loop without
  sync(), which the interpreter's instruction budget puts aside once per
  cycle; (d) movel back and forth. Each on a new core, `seconds` of
  simulated time per run, `runs` runs; median, 99th percentile and largest
  over all runs' cycles, and the median as a share of the control period
  (the cycle has the rest for the node's ROS side).
Figures, not pass/fail: exit status 0 when every measurement ran (every
program ran through its window without stopping).
"""
import argparse
import glob
import os
import time
import xml.etree.ElementTree as ElementTree

import benchlib  # this folder is the script's, first on sys.path

PERIOD = {'ur3': 0.008, 'ur5e': 0.002}
SCRIPT_DIR = os.path.join(benchlib.PACKAGE_DIR, 'test', 'data', 'urscript')
COMPILES_PER_RUN = 20
GENERATED_COMPILES_PER_RUN = 2
GENERATED_LINES = 2000

# Held by a watchdog thread, as users guard a press: force mode ends when the TCP feels more than
# 50 N or has travelled 3 cm. Nothing pushes back on the kinematic arm, so the compliant z axis
# runs at its 5 mm/s limit (as in URSim): 3 cm take 6 s, longer than a run's --seconds should be.
FORCE_MODE_WATCHDOG = '''def pressing_with_watchdog():
  global pressing = True
  global start = get_actual_tcp_pose()
  thread watchdog():
    while pressing:
      if norm(get_tcp_force()) > 50 or pose_dist(get_actual_tcp_pose(), start) > 0.03:
        pressing = False
      end
      sync()
    end
  end
  force_mode(start, [0, 0, 1, 0, 0, 0], [0, 0, 5, 0, 0, 0], 2, [0.1, 0.1, 0.005, 0.17, 0.17, 0.17])
  guard = run watchdog()
  while pressing:
    sync()
  end
  end_force_mode()
  textmsg("watchdog ended the press")
end
'''
# Never waits: each cycle ends when the thread has spent its instruction budget.
TIGHT_LOOP = '''def computing():
  total = 0
  i = 0
  while True:
    i = i + 1
    total = total + sin(i * 0.001) * 2
  end
end
'''
MOVEL_BACK_AND_FORTH = '''def back_and_forth():
  start = get_actual_tcp_pose()
  away = pose_trans(start, p[0.05, 0.03, 0, 0, 0, 0])
  while True:
    movel(away, a=1.2, v=0.25)
    movel(start, a=1.2, v=0.25)
  end
end
'''
PROGRAMS = [
    ('(a) External Control, no program', None),
    ('(b) force_mode with a watchdog thread', FORCE_MODE_WATCHDOG),
    ('(c) tight loop without sync()', TIGHT_LOOP),
    ('(d) movel back and forth (5.8 cm)', MOVEL_BACK_AND_FORTH),
]


def generated_program(lines):
    """A program of `lines` lines: offsets, pose math and a movel per block, as a generator would write."""
    body = ['def generated():', '  base = p[0.3, -0.1, 0.3, 0, 3.1415926, 0]', '  total = 0']
    i = 0
    while len(body) < lines - 1:
        body += ['  offset_%d = p[%.3f, %.3f, %.3f, 0, 0, %.3f]' % (i, 0.001 * (i % 50), 0.002 * (i % 20),
                                                                    0.0005 * (i % 40), 0.01 * (i % 10)),
                 '  target_%d = pose_trans(base, offset_%d)' % (i, i),
                 '  target_%d[2] = target_%d[2] + 0.01 * sin(%d * 0.1) - total / 1000' % (i, i, i),
                 '  total = total + norm([target_%d[0], target_%d[1], target_%d[2]])' % (i, i, i),
                 '  movel(target_%d, a=1.2, v=0.25, r=0.001)' % i]
        i += 1
    return '\n'.join(body[:lines - 1] + ['end']) + '\n'


def controllers_yaml(ur_type):
    import rospkg
    return os.path.join(rospkg.RosPack().get_path('ur_robot_driver'), 'config', '%s_controllers.yaml' % ur_type)


def launch_default(name):
    """The default of an argument of launch/sim_arm.launch: the controllers the node starts with."""
    root = ElementTree.parse(os.path.join(benchlib.PACKAGE_DIR, 'launch', 'sim_arm.launch')).getroot()
    return next(arg.get('default') for arg in root.iter('arg') if arg.get('name') == name)


def new_core(ur_type):
    """The arm's core as the node builds it from its parameters, on the kinematic joints."""
    from ur3_ft_gripper_testing.model import configured
    from ur3_ft_gripper_description.devices.ur_arm import core as arm_core
    from ur3_ft_gripper_description.devices.ur_arm import joints
    from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings
    params = {'~ur_type': ur_type, '~controller_config_file': controllers_yaml(ur_type),
              '~controllers': launch_default('controllers'),
              'robot_description': configured(ur_type, False, False).text}
    settings = read_settings(lambda name, default=None: params.get(name, default))
    return arm_core.ArmCore(settings, joints.KinematicJoints.from_settings(settings))


# -- compile ------------------------------------------------------------------------------------

def time_compile(text, served):
    """(CPU seconds, None or the CompileError's text) of one compile."""
    from ur3_ft_gripper_description import urscript
    started = time.process_time()
    try:
        urscript.compile_script(text, served)
        refused = None
    except urscript.CompileError as exc:
        refused = str(exc)
    return time.process_time() - started, refused


def bench_compile(runs):
    """[(program, lines, [seconds], refusal or None)]; the first row is the process's first compile."""
    served = new_core('ur5e').script_robot.served()  # the e-Series robot offers the most functions
    programs = [(os.path.basename(path), open(path).read(), COMPILES_PER_RUN)
                for path in sorted(glob.glob(os.path.join(SCRIPT_DIR, '*.script')))]
    programs.append(('generated (%d lines)' % GENERATED_LINES, generated_program(GENERATED_LINES),
                     GENERATED_COMPILES_PER_RUN))
    first_text = programs[0][1] if programs else 'textmsg("first")\n'
    seconds, refused = time_compile(first_text, served)
    results = [('first compile in the process (builds the parser): %s' % (
        programs[0][0] if programs else 'one line'), len(first_text.splitlines()), [seconds], refused)]
    times = {name: [] for name, _, _ in programs}
    refusals = {}
    for _ in range(runs):  # interleaved, so that a change of load hits every program alike
        for name, text, count in programs:
            for _ in range(count):
                seconds, refusals[name] = time_compile(text, served)
                times[name].append(seconds)
    for name, text, _ in programs:
        results.append((name, len(text.splitlines()), times[name], refusals[name]))
    return results


# -- per control cycle --------------------------------------------------------------------------

def measure_cycles(ur_type, program, seconds):
    """[CPU seconds of each ArmCore.step] over `seconds` of simulated time; RuntimeError if the program
    stopped within them."""
    core = new_core(ur_type)
    dt = PERIOD[ur_type]
    if program is not None:
        core.script_command(program)
        if not core.script_running:
            raise RuntimeError('%s: the program did not start: %s' % (ur_type, core.take_messages()))
    steps = []
    for _ in range(int(round(seconds / dt))):
        started = time.process_time()
        core.step(dt)
        steps.append(time.process_time() - started)
    if program is not None and not core.script_running:
        raise RuntimeError('%s: the program stopped within %g s: %s' % (ur_type, seconds, core.take_messages()))
    return steps


def bench_cycles(runs, seconds):
    """[(ur_type, case, [step seconds])]."""
    results = []
    for ur_type in ('ur3', 'ur5e'):
        for name, program in PROGRAMS:
            steps = []
            for _ in range(runs):
                steps.extend(measure_cycles(ur_type, program, seconds))
            results.append((ur_type, name, steps))
    return results


# -- report -------------------------------------------------------------------------------------

def section(compiled, cycles, runs, seconds, load):
    lines = [
        "## URScript's cost (`python3 bench/urscript.py`)",
        '',
        '### urscript.py, no ROS, %s' % benchlib.now_text(),
        '',
        'Machine: %s; load average before: %s. Runs: %d; CPU time of this process.' % (
            benchlib.machine(), load, runs),
        '',
        '#### Compile (`urscript.compile_script`, the e-Series robot\'s functions)',
        '',
        '| program | lines | compiles | median (ms) | p99 (ms) | result |',
        '| --- | ---: | ---: | ---: | ---: | --- |',
    ]
    for name, count, times, refused in compiled:
        lines.append('| %s | %d | %d | %.2f | %.2f | %s |' % (
            name, count, len(times), benchlib.median(times) * 1e3, benchlib.percentile(times, 99) * 1e3,
            'refused: %s' % refused.replace('|', '\\|') if refused else 'compiled'))
    lines += [
        '',
        '#### Per control cycle (`ArmCore.step(dt)`, kinematic joints, %g s of simulated time per run)' % seconds,
        '',
        '| ur_type (period) | program | cycles | step median (ms) | p99 (ms) | max (ms) | median / period |',
        '| --- | --- | ---: | ---: | ---: | ---: | ---: |',
    ]
    for ur_type, name, steps in cycles:
        period = PERIOD[ur_type]
        median = benchlib.median(steps)
        lines.append('| %s (%g ms) | %s | %d | %.3f | %.3f | %.3f | %.0f %% |' % (
            ur_type, period * 1e3, name, len(steps), median * 1e3, benchlib.percentile(steps, 99) * 1e3,
            max(steps) * 1e3, 100.0 * median / period))
    return '\n'.join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--runs', type=int, default=5, help='runs of each measurement')
    parser.add_argument('--seconds', type=float, default=1.0,
                        help='simulated time each program runs per run (s, default 1)')
    parser.add_argument('--output', help='RESULTS.md to write the section "urscript" into')
    args = parser.parse_args(argv)
    load = benchlib.load_average()
    compiled = bench_compile(args.runs)
    cycles = bench_cycles(args.runs, args.seconds)
    text = section(compiled, cycles, args.runs, args.seconds, load)
    print(text)
    if args.output:
        benchlib.replace_section(args.output, 'urscript', text)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
