#!/usr/bin/env python3
"""Plants a fault in each of URScript's motion primitives, one at a time, and checks that a test catches it.

Each fault below is a small, plausible bug written as a textual edit of
devices/ur_arm/tool_motion.py. For each one the package's src/ tree is copied
to a temporary folder, the edit is made there (never in the package), and
pytest runs test/unit/test_tool_motion.py and the motion tests of
test/unit/test_ur_arm_core.py (-x -q; the tests named after the fault's
primitive first, so that -x stops early) with the copy first on PYTHONPATH.
A fault is caught when a test fails. The unmutated copy runs first: it must
be what Python imports and its tests must pass, or nothing can be concluded.
Faults run one per CPU at a time. Run in the sourced workspace:

    python3 tools/motion_mutants.py             every fault; a table of what caught each one
    python3 tools/motion_mutants.py --only NAME one fault, or every fault of one primitive (movej, ...)
    python3 tools/motion_mutants.py --list      the faults, without running anything

Exit status 0 when every fault run was caught, 1 when one survived (or the
unmutated tests fail), 2 on bad arguments or when a fault's source text no
longer occurs exactly once in tool_motion.py (the list cannot silently rot).
"""
import argparse
import collections
import concurrent.futures
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

# The real path: pytest 4.6 (Noetic's) names tests wrongly when given them through the workspace's symlink.
PKG_DIR = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
MODULE = os.path.join('ur3_ft_gripper_description', 'devices', 'ur_arm', 'tool_motion.py')
TESTS = [os.path.join(PKG_DIR, 'test', 'unit', 'test_tool_motion.py'),
         os.path.join(PKG_DIR, 'test', 'unit', 'test_ur_arm_core.py')]
# pytest -k: all of test_tool_motion.py, and those of test_ur_arm_core.py that run motions through URScript
# (the rest never reach tool_motion).
SELECTED = 'test_tool_motion or movej or movel or program'
# A fault that makes a motion loop forever is reported (as no verdict), not waited for.
TIMEOUT = 300

Mutant = collections.namedtuple('Mutant', 'name primitive fault source replacement')

MUTANTS = [
    # -- movej
    Mutant('movej-t-ignored', 'movej', "t ignored: the natural trapezoid whatever t",
           'self.profile = Profile(distance, min(v, cap), a, t)',
           'self.profile = Profile(distance, min(v, cap), a)'),
    Mutant('movej-t-past-speed-limit', 'movej', "t has priority even over the joints' speed limits",
           'if self.profile.peak > cap * (1.0 + 1e-9):',
           'if self.profile.peak > cap * (1.0 + 1e-9) and not t:'),
    Mutant('movej-squeezed-from-the-squeezed-peak', 'movej',
           "past the speed limits, the new time scales the squeezed peak instead of the natural one",
           'self.profile.natural * self.profile.v / cap', 'self.profile.natural * self.profile.peak / cap'),
    Mutant('movej-norm-distance', 'movej', "profiled over the joints' Euclidean distance, not the leading joint's",
           'distance = float(np.max(np.abs(self.delta)))',
           'distance = float(np.linalg.norm(self.delta))'),
    Mutant('movej-cap-by-ratio', 'movej', "the speed cap multiplies by the joint's share instead of dividing",
           'float(limit) / ratio for limit, ratio', 'float(limit) * ratio for limit, ratio'),
    Mutant('trapezoid-deceleration-v', 'movej', "the trapezoid decelerates with v in place of a",
           's = self.distance - 0.5 * a * (self.natural - t) ** 2',
           's = self.distance - 0.5 * v * (self.natural - t) ** 2'),
    Mutant('trapezoid-triangle-peak', 'movej', "a triangle's peak from the stopping distance, sqrt(2 d a)",
           'self.v, self.a = math.sqrt(self.distance * a), a',
           'self.v, self.a = math.sqrt(2.0 * self.distance * a), a'),
    Mutant('trapezoid-time-half-ramp', 'movej', "the trapezoid's time counts one ramp at half its length",
           'self.natural = self.distance / v + v / a', 'self.natural = self.distance / v + v / (2.0 * a)'),
    # -- movel
    Mutant('movel-joint-interpolation', 'movel', "interpolates the joints instead of the tool's line",
           'return self._solve(self.pose_at(t), self.q, dt)',
           'return self.start_q + (self.end_q - self.start_q) * self.profile.fraction(t)'),
    Mutant('movel-t-ignored', 'movel', "t ignored",
           'self.profile = Profile(leading.distance, leading.v, leading.a, t)',
           'self.profile = Profile(leading.distance, leading.v, leading.a)'),
    Mutant('movel-rotation-a-unscaled', 'movel', "the rotation accelerates at a rad/s^2, not 4 a",
           'angular = Profile(angle, ROTATION_PER_METRE * v, ROTATION_PER_METRE * a)',
           'angular = Profile(angle, ROTATION_PER_METRE * v, a)'),
    Mutant('movel-shorter-leads', 'movel', "the shorter of the linear and angular profiles sets the time",
           'leading = linear if linear.natural >= angular.natural else angular',
           'leading = linear if linear.natural <= angular.natural else angular'),
    Mutant('movel-turn-in-tool-frame', 'movel', "the base-frame turn applied in the tool frame",
           'pose[:3, 3] = self.start_pose[:3, 3] + fraction * self.line\n'
           '        pose[:3, :3] = rotation_matrix(fraction * self.turn).dot(self.start_pose[:3, :3])',
           'pose[:3, 3] = self.start_pose[:3, 3] + fraction * self.line\n'
           '        pose[:3, :3] = self.start_pose[:3, :3].dot(rotation_matrix(fraction * self.turn))'),
    Mutant('movel-tcp-offset-reversed', 'movel', "tool0 from the TCP by the TCP offset instead of its inverse",
           'return pose if self.tcp_inverse is None else pose.dot(self.tcp_inverse)',
           'return pose if self.tcp_inverse is None else pose.dot(self.tcp)'),
    Mutant('movel-path-unchecked', 'movel', "only the target is checked before moving, not the line to it",
           'steps = max(1, int(math.ceil(self.check_length / CHECK_STEP)))', 'steps = 1'),
    # -- movep
    Mutant('movep-arc-radius', 'movep', "the arc's radius cut * tan(turn / 2) instead of cut / tan(turn / 2)",
           'radius = cut / math.tan(turn / 2.0)', 'radius = cut * math.tan(turn / 2.0)'),
    Mutant('movep-arc-from-rest', 'movep', "the arc starts from rest, not at the speed the tool has",
           'speed = float(np.linalg.norm(previous.tool_speed()))', 'speed = 0.0'),
    Mutant('movep-arc-at-v', 'movep', "the arc starts at the move's v, not at the speed the tool has",
           'speed = float(np.linalg.norm(previous.tool_speed()))', 'speed = float(v)'),
    Mutant('movep-short-stop-at-a', 'movep', "a blend too short to stop in at a still stops at a",
           'return self.distance - 0.5 * self.decel * left * left',
           'return self.distance - 0.5 * self.a * left * left'),
    # -- blends
    Mutant('blend-enters-at-2r', 'blend', "returns (and blends) on entering 2 r",
           'self.returned = self.tool_distance_to_target() <= self.r',
           'self.returned = self.tool_distance_to_target() <= 2.0 * self.r'),
    Mutant('blend-no-overlap', 'blend', "the second move waits for the first to end",
           'return max(0.0, self.previous.remaining() - self.ramp_time())',
           'return max(0.0, self.previous.remaining())'),
    Mutant('blend-starts-early', 'blend', "the second move starts two ramps before the first ends",
           'return max(0.0, self.previous.remaining() - self.ramp_time())',
           'return max(0.0, self.previous.remaining() - 2.0 * self.ramp_time())'),
    Mutant('blend-rotation-dropped', 'blend', "a Cartesian blend superposes positions only, not the rotations",
           '            pose[:3, :3] = mine[:3, :3].dot(self.start_pose[:3, :3].T).dot(pose[:3, :3])\n', ''),
    Mutant('blend-joint-rest-skipped', 'blend', "a joint blend starts from the first move's target",
           'theirs = previous.step(dt)', 'previous.step(dt)\n        theirs = previous.end_q'),
    # -- speedl
    Mutant('speedl-ramp-ignores-aRot', 'speedl', "the angular part ramps at a, not aRot",
           'np.linalg.norm(change[3:]) / self.a_rot)', 'np.linalg.norm(change[3:]) / self.a)'),
    Mutant('speedl-end-twist-integrated', 'speedl', "a cycle moves by its end twist, not its mean",
           'mean = 0.5 * (self.twist + twist)\n        pose = self.pose.copy()',
           'mean = twist\n        pose = self.pose.copy()'),
    Mutant('speedl-t-min-ignored', 'speedl', "older software's t_min returns after t, at speed or not",
           'if self.t > 0.0 and not self.minimum_time:', 'if self.t > 0.0:'),
    Mutant('speedl-limit-scales-linear-only', 'speedl', "at the joints' limits only the linear part is scaled down",
           'twist, reached = twist / excess, False',
           'twist, reached = np.concatenate([twist[:3] / excess, twist[3:]]), False'),
    # -- stopl
    Mutant('stopl-at-half-a', 'stopl', "stops at a / 2",
           'np.zeros(6), a, 0.0, aRot, previous=previous)', 'np.zeros(6), a / 2.0, 0.0, aRot, previous=previous)'),
    Mutant('stopl-ignores-aRot', 'stopl', "the rotation stops at a, not aRot",
           'np.zeros(6), a, 0.0, aRot, previous=previous)', 'np.zeros(6), a, 0.0, None, previous=previous)'),
    # -- speedj
    Mutant('speedj-beyond-limits', 'speedj', "a target beyond the joints' speed limits is not scaled down",
           'self.target = target / excess if excess > 1.0 else target', 'self.target = target'),
    Mutant('speedj-each-joint-at-a', 'speedj', "each joint ramps at a on its own instead of arriving together",
           'speed, reached = self.speed + change * (dt / time_left), False',
           'speed, reached = self.speed + np.clip(change, -self.a * dt, self.a * dt), False'),
    Mutant('speedj-end-speed-integrated', 'speedj', "a cycle moves by its end speed, not its mean",
           'new = self.q + 0.5 * (self.speed + speed) * dt', 'new = self.q + speed * dt'),
    # -- stopj
    Mutant('stopj-at-half-a', 'stopj', "stops at a / 2",
           'np.zeros(6), a, previous=previous)', 'np.zeros(6), a / 2.0, previous=previous)'),
    Mutant('stopj-from-rest', 'stopj', "ramps down from rest, not from the speed the joints have",
           'self.speed = self.qd.copy()', 'self.speed = np.zeros_like(self.qd)'),
    # -- servoj
    Mutant('servoj-lookahead-ignored', 'servoj', "the default lookahead time whatever lookahead_time",
           'follow(self.q, self.target, dt, self.lookahead_time,',
           'follow(self.q, self.target, dt, SERVOJ_LOOKAHEAD_TIME,'),
    Mutant('servoj-returns-each-cycle', 'servoj', "returns after one cycle, not after t",
           'if self.elapsed >= self.t - 1e-9:', 'if self.elapsed > 0.0:'),
    Mutant('servoj-limits-unchecked', 'servoj', "a target beyond the joint limits is followed up to them, not refused",
           "        self._check_limits(target, 'servoj')\n", ''),
    Mutant('servoj-speed-unlimited', 'servoj', "the joints follow beyond their speed limits",
           'self.arm.velocity, self.arm.lower,', 'np.inf * self.arm.velocity, self.arm.lower,'),
]

PRIMITIVES = sorted(set(m.primitive for m in MUTANTS))

# caught: True, False, or None when pytest gave no verdict (caught_by then says why).
Result = collections.namedtuple('Result', 'mutant caught caught_by seconds')


def module_text():
    with open(os.path.join(PKG_DIR, 'src', MODULE)) as f:
        return f.read()


def stale(text, mutants=MUTANTS):
    """(name, occurrences) of each fault whose source text is not in `text` exactly once."""
    return [(m.name, text.count(m.source)) for m in mutants if text.count(m.source) != 1]


def mutate(text, mutant):
    """tool_motion.py's text with `mutant` planted; ValueError (one line) if it does not apply once."""
    found = text.count(mutant.source)
    if found != 1:
        raise ValueError('%s: its source text occurs %d times in tool_motion.py, not once' % (mutant.name, found))
    mutated = text.replace(mutant.source, mutant.replacement)
    compile(mutated, MODULE, 'exec')  # a fault is a wrong motion, not a broken module
    return mutated


def copy_src(folder, text):
    """src/ copied into `folder` with tool_motion.py's text `text`; the copy's src folder."""
    src = os.path.join(folder, 'src')
    # Without the package's bytecode: a stale .pyc must not stand in for the edited module.
    shutil.copytree(os.path.join(PKG_DIR, 'src'), src, ignore=shutil.ignore_patterns('__pycache__', '*.pyc'))
    with open(os.path.join(src, MODULE), 'w') as f:
        f.write(text)
    return src


def environment(src):
    env = dict(os.environ)
    # The copy before the workspace's devel space, whose relay would import the package's own src/.
    env['PYTHONPATH'] = os.pathsep.join([src] + [p for p in env.get('PYTHONPATH', '').split(os.pathsep) if p])
    env['PYTHONDONTWRITEBYTECODE'] = '1'
    return env


def imported_from(src):
    """Where a Python with the copy first on its path finds tool_motion.py."""
    run = subprocess.run([sys.executable, '-c', 'import ur3_ft_gripper_description.devices.ur_arm.tool_motion as m; '
                          'print(m.__file__)'], env=environment(src), cwd=os.path.dirname(src),
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
    return run.stdout.strip()


def pytest_command(*args):
    # --rootdir: node ids relative to the package whatever the folder the tests run from.
    # -rf: the short summary names the failed test in every pytest (4.6 on Noetic prints none without it).
    return [sys.executable, '-m', 'pytest', '-q', '-rf', '-p', 'no:cacheprovider', '--rootdir', PKG_DIR] + list(args)


def collect(src):
    """The node ids (absolute paths) of the tests that are run, in their files' order."""
    run = subprocess.run(pytest_command('--collect-only', '-k', SELECTED, *TESTS), env=environment(src),
                         cwd=os.path.dirname(src), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         universal_newlines=True, timeout=TIMEOUT)
    return [os.path.join(PKG_DIR, line.strip()) for line in run.stdout.splitlines() if '::' in line]


def first_for(tests, primitive):
    """`tests` with those named after `primitive` first: with -x, a fault in one is usually found at once."""
    mine = [test for test in tests if primitive in test.split('::', 1)[1].lower()]
    return mine + [test for test in tests if test not in mine]


def run_tests(src, tests):
    """(passed, the first failing test's name or a reason, seconds) of `tests` against the copy `src`."""
    started = time.monotonic()
    try:
        run = subprocess.run(pytest_command('-x', *tests), env=environment(src), cwd=os.path.dirname(src),
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
                             timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return None, 'timed out after %d s' % TIMEOUT, time.monotonic() - started
    seconds = time.monotonic() - started
    if run.returncode == 0:
        return True, '', seconds
    failed = re.search(r'^FAILED (\S+?)(?: - |$)', run.stdout, re.MULTILINE)
    if run.returncode == 1 and failed:
        return False, failed.group(1).split('::', 1)[-1], seconds
    # Not a test's verdict (a collection error, an internal error): the last lines say why.
    last = [line for line in run.stdout.splitlines() if line.strip()][-3:]
    return None, 'pytest exit %d: %s' % (run.returncode, ' | '.join(last)), seconds


def run_one(text, tests, mutant):
    """The tests against a copy of src/ with `mutant` planted."""
    with tempfile.TemporaryDirectory(prefix='motion_mutant_') as folder:
        src = copy_src(folder, mutate(text, mutant))
        passed, detail, seconds = run_tests(src, first_for(tests, mutant.primitive))
    return Result(mutant, None if passed is None else not passed, detail, seconds)


def run_baseline(text):
    """(the unmutated run's Result, the tests' node ids): the copy must be what Python imports, and pass."""
    with tempfile.TemporaryDirectory(prefix='motion_mutant_') as folder:
        src = copy_src(folder, text)
        where = imported_from(src)
        if where != os.path.join(src, MODULE):
            return Result(None, None, 'the copy of src/ is not what Python imports (%s)' % where, 0.0), []
        tests = collect(src)
        if not tests:
            return Result(None, None, 'no tests collected from %s' % ', '.join(TESTS), 0.0), []
        passed, detail, seconds = run_tests(src, tests)
    return Result(None, None if passed is None else not passed, detail, seconds), tests


def run_all(mutants, jobs=None):
    """Results of the unmutated run (first) and of each mutant; the mutants only if the first passed."""
    text = module_text()
    baseline, tests = run_baseline(text)
    if baseline.caught is not False:
        return baseline, []
    jobs = jobs or max(1, os.cpu_count() or 1)
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        results = list(pool.map(lambda m: run_one(text, tests, m), mutants))
    return baseline, results


def select(only):
    if only is None:
        return MUTANTS
    chosen = [m for m in MUTANTS if only in (m.name, m.primitive)]
    if not chosen:
        raise ValueError('no fault or primitive named %r (primitives: %s; --list names the faults)'
                         % (only, ', '.join(PRIMITIVES)))
    return chosen


def table(rows, header):
    widths = [max(len(str(r[i])) for r in [header] + rows) for i in range(len(header))]
    return '\n'.join('  '.join(str(c).ljust(w) for c, w in zip(r, widths)).rstrip() for r in [header] + rows)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--only', metavar='NAME', help='one fault, or every fault of one primitive')
    parser.add_argument('--list', action='store_true', help='list the faults and exit')
    parser.add_argument('--jobs', type=int, default=0, help='faults run at once (default: one per CPU)')
    args = parser.parse_args(argv)
    try:
        mutants = select(args.only)
    except ValueError as error:
        print('motion_mutants: %s' % error, file=sys.stderr)
        return 2
    if args.list:
        print(table([(m.primitive, m.name, m.fault) for m in mutants], ('primitive', 'fault', 'what it does')))
        return 0
    rotten = stale(module_text(), mutants)
    if rotten:
        print('motion_mutants: the source text of %s no longer occurs exactly once in tool_motion.py: update MUTANTS'
              % ', '.join('%s (%d times)' % r for r in rotten), file=sys.stderr)
        return 2
    text = module_text()
    for mutant in mutants:
        try:
            mutate(text, mutant)
        except SyntaxError as error:
            print('motion_mutants: %s: the edited module does not compile (%s, line %s)'
                  % (mutant.name, error.msg, error.lineno), file=sys.stderr)
            return 2
    started = time.monotonic()
    baseline, results = run_all(mutants, args.jobs)
    if baseline.caught is not False:
        print('motion_mutants: the unmutated run does not pass (%s): fix that first' % baseline.caught_by,
              file=sys.stderr)
        return 1
    rows = []
    for r in results:
        verdict = r.caught_by if r.caught else ('SURVIVED' if r.caught is False else 'ERROR: %s' % r.caught_by)
        rows.append((r.mutant.primitive, r.mutant.name, verdict, '%.1f s' % r.seconds))
    print(table(rows, ('primitive', 'fault', 'caught by', 'time')))
    missed = [r.mutant.name for r in results if not r.caught]
    print('%d of %d faults caught in %.0f s (unmutated tests: %.1f s)%s'
          % (len(results) - len(missed), len(results), time.monotonic() - started, baseline.seconds,
             '; not caught: ' + ', '.join(missed) if missed else ''))
    return 1 if missed else 0


if __name__ == '__main__':
    sys.exit(main())
