"""tools/run_tests.py shows progress while the tests run; tools/test_summary.py's closing line stays CI's.

A small catkin-like build folder stands in for the workspace: a real make
with run_tests_<package>_* targets that write JUnit files (one passes, one
fails, one sleeps long enough for the live line to tick), so the progress is
checked without running the package's own suite.
"""
import os
import pty
import re
import select
import subprocess
import sys

PKG_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RUN_TESTS = os.path.join(PKG_DIR, 'tools', 'run_tests.py')
TEST_SUMMARY = os.path.join(PKG_DIR, 'tools', 'test_summary.py')
# CI (.ci/run) takes its counts from the last line matching this.
CI_LINE = re.compile(r'tests: [0-9]+ passed, [0-9]+ failed')

PASSING = '<testsuite name="a"><testcase name="test_one"/><testcase name="test_two"/></testsuite>'
# As rosunit writes a failure: the assertion first, then the traceback.
FAILING = ('<testsuite name="b"><testcase name="test_fine"/>'
           '<testcase name="test_broken"><failure type="AssertionError">19.1 != 20.0 within 0.5 delta&#10;'
           '  File "check.py", line 7, in test_broken&#10;    self.assertAlmostEqual(fz, 20.0, delta=0.5)'
           '</failure></testcase></testsuite>')
WHY = '        19.1 != 20.0 within 0.5 delta'  # the failure's reason, under its FAILED line
MAKEFILE = '''\
RESULTS = test_results/pkg
help:
\t@echo "The following are some of the valid targets for this Makefile:"
\t@echo "... all (the default if no target is provided)"
\t@echo "... run_tests_pkg"
\t@echo "... run_tests_pkg_pytest"
\t@echo "... run_tests_pkg_pytest_unit"
\t@echo "... run_tests_pkg_pytest_unit_more"
\t@echo "... run_tests_pkg_rostest"
\t@echo "... run_tests_pkg_rostest_test_rostest_broken.test"
\t@echo "... run_tests_pkg_rostest_test_rostest_slow.test"
\t@echo "... _run_tests_pkg_rostest_test_rostest_slow.test"
run_tests_pkg_pytest_unit:
\t@mkdir -p $(RESULTS) && echo '%s' > $(RESULTS)/pytest-unit.xml && echo unit ran
run_tests_pkg_pytest_unit_more:
\t@mkdir -p $(RESULTS) && echo '%s' > $(RESULTS)/pytest-unit_more.xml
run_tests_pkg_rostest_test_rostest_broken.test:
\t@mkdir -p $(RESULTS) && echo '%s' > $(RESULTS)/rostest-broken.xml && echo broken ran
run_tests_pkg_rostest_test_rostest_slow.test:
\t@sleep 2.5 && mkdir -p $(RESULTS) && echo '%s' > $(RESULTS)/rostest-slow.xml
''' % (PASSING, PASSING.replace('name="a"', 'name="d"'), FAILING, PASSING.replace('name="a"', 'name="c"'))


def build_folder(tmp_path):
    build = tmp_path / 'build'
    build.mkdir()
    (build / 'Makefile').write_text(MAKEFILE)
    return build


def run_tests_args(build, tmp_path, *extra):
    return [sys.executable, RUN_TESTS, 'catkin', '--build', str(build), '--package', 'pkg', '--label', 'variant',
            '--log', str(tmp_path / 'tests.log')] + list(extra)


def test_plain_output_names_each_file_as_it_starts_and_each_failure_before_the_next(tmp_path):
    build = build_folder(tmp_path)
    run = subprocess.run(run_tests_args(build, tmp_path), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True, timeout=120)
    assert run.returncode == 0, run.stderr
    lines = run.stderr.splitlines()
    assert '\r' not in run.stderr, 'a pipe gets plain lines, no carriage-return updates'
    # pytest first, then the rostests: leaf targets only (unit_more too, though its name extends unit's),
    # one line each as it starts.
    assert [re.sub(r', \d+:\d\d$', '', l) for l in lines] == [
        '[tests] variant 1/4 pytest unit: 0 failed so far',
        '[tests] variant 2/4 pytest unit_more: 0 failed so far',
        '[tests] variant 3/4 rostest broken.test: 0 failed so far',
        'FAILED  variant/rostest-broken.xml: test_broken',
        WHY,
        '[tests] variant 4/4 rostest slow.test: 1 failed so far',
        '[tests] variant: 7 passed, 1 failed',
    ], run.stderr
    assert not any(CI_LINE.search(l) for l in lines), 'only the closing summary may look like CI\'s line'
    log = (tmp_path / 'tests.log').read_text()
    assert 'unit ran' in log and 'broken ran' in log, 'the tests\' own output goes to the log'


def test_on_a_terminal_one_line_updates_in_place_and_a_failure_gets_its_own_line(tmp_path):
    build = build_folder(tmp_path)
    master, slave = pty.openpty()
    child = subprocess.Popen(run_tests_args(build, tmp_path), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                             stderr=slave)
    os.close(slave)
    output = b''
    while True:
        ready, _, _ = select.select([master], [], [], 60)
        if not ready:
            break
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        output += chunk
    os.close(master)
    assert child.wait(timeout=60) == 0
    text = output.decode()
    screens = text.split('\r')
    slow = [s for s in screens if s.startswith('[tests] variant 4/4 rostest slow.test')]
    assert len(slow) >= 2, 'the line of a running file is redrawn while it runs (elapsed time): %r' % text
    assert '\r\x1b[KFAILED  variant/rostest-broken.xml: test_broken\n%s\n' % WHY in text.replace('\r\n', '\n'), text
    assert text.replace('\r\n', '\n').endswith('\n'), 'the last status line is ended, the next output starts clean'


def test_failures_counted_before_count_in_failed_so_far(tmp_path):
    build = build_folder(tmp_path)
    earlier = tmp_path / 'earlier'
    earlier.mkdir()
    (earlier / 'old.xml').write_text(FAILING)
    run = subprocess.run(run_tests_args(build, tmp_path, '--counted', str(earlier), '--plain'),
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         universal_newlines=True, timeout=120)
    assert '[tests] variant 1/4 pytest unit: 1 failed so far' in run.stderr, run.stderr
    assert '[tests] variant 4/4 rostest slow.test: 2 failed so far' in run.stderr, run.stderr


def test_the_log_gives_each_jobs_cpu_time_and_its_own_time(tmp_path):
    result = tmp_path / 'busy.xml'
    # Half a second of CPU in a grandchild (make runs the targets so), then the result.
    command = ('import subprocess, sys, time; subprocess.run([sys.executable, "-c", "import time\\n'
               'end = time.process_time() + 0.5\\nwhile time.process_time() < end: pass"]); '
               'time.sleep(0.5); open(sys.argv[1], "w").write(%r)' % PASSING)
    run = subprocess.run([sys.executable, RUN_TESTS, 'command', '--label', 'busy', '--log', str(tmp_path / 'b.log'),
                          '--results', str(result), '--', sys.executable, '-c', command, str(result)],
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         universal_newlines=True, timeout=60)
    assert run.returncode == 0, run.stderr
    cpu, wall = map(float, re.search(r'^=== .*: ([\d.]+) s of CPU over ([\d.]+) s$',
                                     (tmp_path / 'b.log').read_text(), re.MULTILINE).groups())
    assert 0.5 <= cpu < wall, (cpu, wall)


def test_a_command_job_reports_like_a_target(tmp_path):
    result = tmp_path / 'tools.xml'
    command = 'import sys; open(sys.argv[1], "w").write(%r)' % FAILING
    run = subprocess.run([sys.executable, RUN_TESTS, 'command', '--label', 'test/tools', '--log',
                          str(tmp_path / 'tools.log'), '--results', str(result), '--',
                          sys.executable, '-c', command, str(result)],
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         universal_newlines=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert re.sub(r', \d+:\d\d$', '', run.stderr.splitlines()[0]) == '[tests] test/tools 1/1: 0 failed so far'
    lines = run.stderr.splitlines()
    assert lines[lines.index('FAILED  test/tools/tools.xml: test_broken') + 1] == WHY, run.stderr


def test_a_job_that_writes_no_result_is_reported(tmp_path):
    run = subprocess.run([sys.executable, RUN_TESTS, 'command', '--label', 'lint', '--log', str(tmp_path / 'l.log'),
                          '--results', str(tmp_path / 'none.xml'), '--', 'false'],
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         universal_newlines=True, timeout=60)
    assert run.returncode == 1
    assert 'false exited 1 and wrote no result' in run.stderr, run.stderr


def test_the_closing_line_is_the_one_ci_reads(tmp_path):
    (tmp_path / 'robotiq-noetic').mkdir()
    (tmp_path / 'robotiq-noetic' / 'a.xml').write_text(PASSING)
    (tmp_path / 'robotiq-noetic' / 'b.xml').write_text(FAILING)
    run = subprocess.run([sys.executable, TEST_SUMMARY, str(tmp_path)], stdout=subprocess.PIPE,
                         universal_newlines=True)
    assert run.returncode == 1
    assert run.stdout.splitlines() == ['FAILED  robotiq-noetic/b.xml: test_broken', WHY, 'tests: 3 passed, 1 failed']
    assert CI_LINE.fullmatch(run.stdout.splitlines()[-1])


if __name__ == '__main__':
    sys.exit(subprocess.call([sys.executable, '-m', 'pytest', __file__]))


def test_the_cell_targets_of_the_scope_file_are_left_out_and_the_rest_run(tmp_path):
    scope = tmp_path / 'scope.yaml'
    scope.write_text('cell_targets:\n  rostest: [broken.test]\n')
    run = subprocess.run(run_tests_args(build_folder(tmp_path), tmp_path, '--plain', '--cell-tests-elsewhere',
                                        str(scope)),
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         universal_newlines=True, timeout=120)
    assert run.returncode == 0, run.stderr
    lines = [re.sub(r', \d+:\d\d$', '', l) for l in run.stderr.splitlines()]
    assert lines == [
        "[tests] variant: the cell's 1 targets run in another variant's pass (scope.yaml)",
        '[tests] variant 1/3 pytest unit: 0 failed so far',
        '[tests] variant 2/3 pytest unit_more: 0 failed so far',
        '[tests] variant 3/3 rostest slow.test: 0 failed so far',
        '[tests] variant: 6 passed, 0 failed',
    ], run.stderr
    assert 'broken ran' not in (tmp_path / 'tests.log').read_text()


def test_a_scope_file_naming_a_target_the_build_has_not_stops_before_any_test_runs(tmp_path):
    scope = tmp_path / 'scope.yaml'
    scope.write_text('cell_targets:\n  rostest: [broken.test, renamed.test]\n')
    run = subprocess.run(run_tests_args(build_folder(tmp_path), tmp_path, '--cell-tests-elsewhere', str(scope)),
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         universal_newlines=True, timeout=120)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        'run_tests: %s names targets %s has not: rostest/renamed.test (rename them there too)'
        % (scope, tmp_path / 'build')], run.stderr
    assert not (tmp_path / 'tests.log').exists() or 'ran' not in (tmp_path / 'tests.log').read_text()
