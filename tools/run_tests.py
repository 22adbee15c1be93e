#!/usr/bin/env python3
"""Run a package's catkin test targets one at a time, showing progress as they run.

What `catkin_make run_tests_<package> -j1` runs, target by target, so that the
user sees which test file is running, how many of how many, the failures so
far and the elapsed time, and each failure's name as soon as its file has
run. On a terminal that is one line updated in place; otherwise (CI's log is
a pipe) one plain line per test file. The output of the tests goes to --log.
Failures are counted by tools/test_summary.py's Tally, as in the closing line.

    run_tests.py catkin --build WS/build --package ur3_ft_gripper_description --label robotiq-noetic \
        --log run_tests.log [--counted RESULTS_SO_FAR] [--started EPOCH_SECONDS] \
        [--cell-tests-elsewhere test/variant_scope.yaml]
    run_tests.py command --results tools.xml --label test/tools --log tools.log -- python3 -m pytest ...

Exit status 0 when every job ran and wrote results (whatever the tests'
outcome: the closing summary counts that), 1 if one exited non-zero without
writing any, 2 on bad arguments.
"""
import argparse
import os
import re
import resource
import shutil
import subprocess
import sys
import time

import yaml

import test_summary

TARGET_TYPES = ('pytest', 'roslaunch-check', 'rostest', 'gtest', 'nosetests')


def test_targets(build_dir, package):
    """The leaf run_tests targets of `package` in build_dir, grouped by type as catkin names them."""
    run = subprocess.run(['make', '-C', build_dir, 'help'], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         universal_newlines=True)
    if run.returncode != 0:
        raise SystemExit('run_tests: `make -C %s help` failed: is it a configured catkin build folder?\n%s'
                         % (build_dir, run.stderr.strip()))
    prefix = 'run_tests_%s_' % package
    names = sorted(set(re.findall(r'^\.\.\. (%s\S+)$' % re.escape(prefix), run.stdout, re.MULTILINE)))
    # run_tests_<package>_<type> (run_tests_<package>_rostest) only groups the targets of its type.
    groups = {prefix + kind for kind in TARGET_TYPES}
    leaves = [n for n in names if n not in groups]
    order = {kind: i for i, kind in enumerate(TARGET_TYPES)}
    return sorted(leaves, key=lambda n: (order.get(short_name(n, package)[0], len(order)), n))


def short_name(target, package):
    """('rostest', 'tf_chain.test') for run_tests_<package>_rostest_test_rostest_tf_chain.test."""
    rest = target[len('run_tests_%s_' % package):]
    for kind in TARGET_TYPES:
        if rest.startswith(kind + '_'):
            name = rest[len(kind) + 1:]
            if kind == 'rostest':
                name = name.rsplit('_rostest_', 1)[-1] if '_rostest_' in name else name
            return kind, name
    return '', rest


def cell_targets(scope_file):
    """{(kind, name)} of the cell's targets that test/variant_scope.yaml names: they run in one
    robotiq variant's pass per machine, so the other passes leave them out."""
    with open(scope_file) as stream:
        listed = (yaml.safe_load(stream) or {}).get('cell_targets') or {}
    return {(kind, name) for kind, names in listed.items() for name in names}


def clock(seconds):
    seconds = int(seconds)
    return '%d:%02d:%02d' % (seconds // 3600, seconds // 60 % 60, seconds % 60) if seconds >= 3600 \
        else '%d:%02d' % (seconds // 60, seconds % 60)


class Progress(object):
    """The status line: rewritten in place on a terminal, one plain line per change otherwise."""

    def __init__(self, stream, live):
        self.stream, self.live, self.shown = stream, live, ''

    def fit(self, text):
        return text[:shutil.get_terminal_size((100, 20)).columns - 1]

    def status(self, text):
        if self.live:
            self.stream.write('\r' + self.fit(text) + '\033[K')
            self.shown = text
        else:
            self.stream.write(text + '\n')
        self.stream.flush()

    def say(self, text):
        """A line of its own (a failure), with the status line redrawn below it."""
        if self.live:
            self.stream.write('\r\033[K' + text + '\n' + self.fit(self.shown))
        else:
            self.stream.write(text + '\n')
        self.stream.flush()

    def done(self):
        if self.live and self.shown:
            self.stream.write('\n')
            self.stream.flush()


def run_jobs(jobs, results, args, stream):
    """Run each (kind, name, argv) of `jobs` in turn, its output appended to args.log; after
    each, count the result files new or changed in `results` and print their failures."""
    started = args.started if args.started is not None else time.time()
    so_far = test_summary.tally(args.counted) if args.counted and os.path.isdir(args.counted) else test_summary.Tally()
    counted = test_summary.Tally()
    progress = Progress(stream, stream.isatty() if args.live is None else args.live)
    seen = {path: os.stat(path).st_mtime for path, _ in existing_results(results)}
    status = 0
    with open(args.log, 'a') as log:
        for index, (kind, name, argv) in enumerate(jobs, 1):

            def line():
                failed = len(so_far.failed) + len(so_far.skipped) + len(counted.failed) + len(counted.skipped)
                what = ' '.join(filter(None, ('%d/%d' % (index, len(jobs)), kind, name)))
                return '[tests] %s %s: %d failed so far, %s' % (args.label, what, failed, clock(time.time() - started))

            progress.status(line())
            log.write('\n=== %s\n' % ' '.join(argv))
            log.flush()
            job_started, used_before = time.time(), cpu_of_children()
            child = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT)
            try:
                while True:
                    try:
                        child.wait(timeout=1.0)
                        break
                    except subprocess.TimeoutExpired:
                        if progress.live:
                            progress.status(line())
            except BaseException:
                child.terminate()
                child.wait()
                progress.done()
                raise
            # Where the suite's time goes: a job that keeps a CPU busy for its whole time is the one to make
            # leaner; one that waits (on the wall clock, on another process) shares the machine.
            log.write('=== %s: %.1f s of CPU over %.1f s\n' % (
                ' '.join(filter(None, (kind, name))) or ' '.join(argv), cpu_of_children() - used_before,
                time.time() - job_started))
            log.flush()
            new = [(path, where) for path, where in existing_results(results)
                   if seen.get(path) != os.stat(path).st_mtime]
            if child.returncode != 0 and not new:
                progress.say('[tests] %s: %s exited %d and wrote no result, see %s' % (
                    args.label, ' '.join(argv), child.returncode, args.log))
                status = 1
            for path, where in new:
                seen[path] = os.stat(path).st_mtime
                skipped = len(counted.skipped)
                for label in counted.add_file(path, os.path.join(args.label, where)):
                    progress.say(counted.failed_line(label))
                for label in counted.skipped[skipped:]:
                    progress.say('SKIPPED ' + label)
    progress.status('[tests] %s: %d passed, %d failed%s, %s' % (
        args.label, counted.passed, len(counted.failed),
        ', %d skipped' % len(counted.skipped) if counted.skipped else '', clock(time.time() - started)))
    progress.done()
    return status


def cpu_of_children():
    """CPU seconds (user and system) of every process this one has waited for, and of theirs."""
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def existing_results(results):
    """(path, path relative to the results folder) of each result file; `results` may be one file."""
    if os.path.isfile(results):
        return [(results, os.path.basename(results))]
    return list(test_summary.result_files(results)) if os.path.isdir(results) else []


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    commands = parser.add_subparsers(dest='command')
    catkin = commands.add_parser('catkin', help="a package's catkin test targets, one at a time")
    catkin.add_argument('--build', required=True, help='the catkin build folder')
    catkin.add_argument('--package', required=True)
    catkin.add_argument('--cell-tests-elsewhere', metavar='SCOPE_FILE',
                        help="leave out the cell's targets SCOPE_FILE names: another variant's pass runs them")
    command = commands.add_parser('command', help='one command that writes JUnit results')
    command.add_argument('--results', required=True, help='the result file, or the folder, it writes')
    command.add_argument('argv', nargs=argparse.REMAINDER, help='-- the command and its arguments')
    for sub in (catkin, command):
        sub.add_argument('--label', required=True, help='names this run in the output, e.g. robotiq-noetic')
        sub.add_argument('--log', required=True, help="file the tests' own output is appended to")
        sub.add_argument('--counted', help='results counted before: their failures count in "failed so far"')
        sub.add_argument('--started', type=float, help='epoch seconds the elapsed time counts from (default: now)')
        live = sub.add_mutually_exclusive_group()
        live.add_argument('--live', dest='live', action='store_true', default=None,
                          help='update one line in place (default: when stderr is a terminal)')
        live.add_argument('--plain', dest='live', action='store_false', help='one line per test file')
    args = parser.parse_args(argv)
    if args.command == 'catkin':
        targets = test_targets(args.build, args.package)
        if not targets:
            parser.exit(2, 'run_tests: %s has no run_tests_%s_* targets: was it configured with '
                           '-DCATKIN_ENABLE_TESTING=ON?\n' % (args.build, args.package))
        jobs = [short_name(t, args.package) + (['make', '-C', args.build, '-j1', t],) for t in targets]
        if args.cell_tests_elsewhere:
            elsewhere = cell_targets(args.cell_tests_elsewhere)
            unknown = sorted('%s/%s' % pair for pair in elsewhere - {job[:2] for job in jobs})
            if unknown:
                parser.exit(2, 'run_tests: %s names targets %s has not: %s (rename them there too)\n'
                            % (args.cell_tests_elsewhere, args.build, ', '.join(unknown)))
            jobs = [job for job in jobs if job[:2] not in elsewhere]
            sys.stderr.write('[tests] %s: the cell\'s %d targets run in another variant\'s pass (%s)\n'
                             % (args.label, len(elsewhere), os.path.basename(args.cell_tests_elsewhere)))
        results = os.path.join(args.build, 'test_results', args.package)
    elif args.command == 'command':
        argv = args.argv[1:] if args.argv[:1] == ['--'] else args.argv
        if not argv:
            parser.exit(2, 'run_tests: command: no command given after --\n')
        jobs, results = [('', '', argv)], args.results
    else:
        parser.exit(2, parser.format_usage())
    return run_jobs(jobs, results, args, sys.stderr)


if __name__ == '__main__':
    sys.exit(main())
