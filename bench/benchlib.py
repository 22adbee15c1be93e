"""Shared by bench/benchmarks.py and bench/soak.py: own ROS master, processes, numbers, RESULTS.md.

Everything here starts its own rosmaster on a free port, so a benchmark never
touches a master someone else uses, and stops only the processes it started.
"""
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import xmlrpc.client

# Free ports, masters, stopping processes and waiting: the tests' helpers, one home for both.
from ur3_ft_gripper_testing.rostest_helpers import (  # noqa: F401
    free_port, master_pid, stop_group, wait_for, wait_for_result)

BENCH_DIR = os.path.dirname(os.path.abspath(__file__))
PACKAGE_DIR = os.path.dirname(BENCH_DIR)
CLK_TCK = os.sysconf('SC_CLK_TCK')

# Every process started here leads a session of its own, and is stopped with its whole group:
# SIGINT first (what roslaunch and rospy expect), then SIGKILL for whatever is left, e.g. the
# rosmaster of a roslaunch that would not end. Callers stop in `finally`, so that a failed
# measurement leaves nothing running.
stop = stop_group


def use_new_master():
    """Start a rosmaster on a free port and point this process (and its children) at it."""
    port = free_port()
    uri = 'http://localhost:%d' % port
    os.environ['ROS_MASTER_URI'] = uri
    log = open(os.devnull, 'w')
    process = subprocess.Popen(['rosmaster', '--core', '-p', str(port)], stdout=log, stderr=log,
                               start_new_session=True)
    try:
        wait_for(lambda: master_pid(uri), 'rosmaster on port %d' % port, 30)
    except BaseException:
        stop(process)
        raise
    return process


def roslaunch(*args, env=None, log=None):
    out = open(log, 'w') if log else subprocess.DEVNULL
    return subprocess.Popen(['roslaunch'] + list(args), stdout=out, stderr=subprocess.STDOUT,
                            env=env, start_new_session=True)


def node(script, *args, env=None):
    """One of this package's nodes, run directly so that its pid is the node's."""
    return subprocess.Popen([sys.executable, os.path.join(PACKAGE_DIR, 'scripts', script)] + list(args),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, start_new_session=True)


def node_pid(name):
    """pid of a running ROS node, from its own slave API."""
    import rosnode
    uri = rosnode.get_api_uri(rosnode.rosgraph.Master('/bench'), name)
    return xmlrpc.client.ServerProxy(uri).getPid('/bench')[2]


def cpu_seconds(pid):
    with open('/proc/%d/stat' % pid) as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime + stime


def rss_mb(pid):
    with open('/proc/%d/status' % pid) as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError('no VmRSS for pid %d' % pid)


def percentile(values, q):
    """The q-th percentile (q in 1..99), nan for no values."""
    if len(values) < 2:
        return float(values[0]) if values else float('nan')
    return statistics.quantiles(values, n=100, method='inclusive')[q - 1]


def median(values):
    return statistics.median(values) if values else float('nan')


def load_average():
    return '%.2f %.2f %.2f' % os.getloadavg()


def machine():
    cpu = platform.processor() or 'unknown CPU'
    try:
        with open('/proc/cpuinfo') as f:
            cpu = next(line.split(':', 1)[1].strip() for line in f if line.startswith('model name'))
    except (OSError, StopIteration):
        pass
    with open('/proc/meminfo') as f:
        mem = int(f.readline().split()[1]) / 1024.0 / 1024.0
    distro = ''
    try:  # platform.freedesktop_os_release needs Python 3.10; Noetic has 3.8
        with open('/etc/os-release') as f:
            fields = dict(line.rstrip('\n').split('=', 1) for line in f if '=' in line)
        distro = fields.get('PRETTY_NAME', '').strip('"')
    except OSError:
        pass
    return '%s, %d CPUs, %.1f GB RAM, %s, Linux %s, Python %s' % (
        cpu, os.cpu_count(), mem, distro, platform.release(), platform.python_version())


def now_text():
    return datetime.datetime.now().astimezone().strftime('%Y-%m-%d %H:%M %Z')


def replace_section(path, key, text):
    """Put `text` between <!-- begin KEY --> and <!-- end KEY --> in `path`, keeping the rest."""
    begin, end = '<!-- begin %s -->' % key, '<!-- end %s -->' % key
    old = open(path).read() if os.path.exists(path) else ''
    block = '%s\n%s\n%s' % (begin, text.strip(), end)
    if begin in old and end in old:
        head, rest = old.split(begin, 1)
        new = head + block + rest.split(end, 1)[1]
    else:
        new = (old.rstrip() + '\n\n' if old.strip() else '') + block + '\n'
    with open(path, 'w') as f:
        f.write(new)


def report_soak(record, section, heading, setting, load_before, rows, problems, label):
    """Print a soak's table and verdict; with `record` (a RESULTS.md), write them into its `section` too.

    `setting`: one sentence on what ran; `rows`: '| what | figures |' lines. The exit status: 0 if no problems.
    """
    verdict = 'PASS' if not problems else 'FAIL: ' + '; '.join(problems[:10]) + (
        ' (and %d more)' % (len(problems) - 10) if len(problems) > 10 else '')
    table = '\n'.join(['| | |', '| --- | --- |'] + rows)
    print(table)
    print('%s: %s' % (label, verdict))
    if record:
        replace_section(record, section, '\n'.join([
            heading, '', '%s, %s; load average before: %s. %s' % (now_text(), machine(), load_before, setting), '',
            table, '', 'Result: %s' % verdict]))
    return 0 if not problems else 1


def measure_alone(node_name, measure):
    """In a process of its own (rospy talks to one master per process): a new master, a node, then
    measure(rospy)'s result printed as JSON; everything started is stopped."""
    master = use_new_master()
    try:
        import rospy
        rospy.init_node(node_name, disable_signals=True)
        try:
            print(json.dumps(measure(rospy)))
        finally:
            rospy.signal_shutdown('done')
    finally:
        stop(master)
    return 0


def measure_each(script, names, args, say):
    """[the JSON `script --one NAME args...` prints last, for each NAME], or None if one failed.

    Each runs in its own session, so that it ends through stop() (SIGINT), which it answers by
    stopping everything it started, also when this process is interrupted.
    """
    results = []
    for name in names:
        child = subprocess.Popen([sys.executable, script, '--one', name] + list(args), stdout=subprocess.PIPE,
                                 universal_newlines=True, start_new_session=True)
        try:
            output, _ = child.communicate()
        finally:
            stop(child)
        if child.returncode != 0:
            say('%s: the measurement failed (exit status %d)' % (name, child.returncode))
            return None
        results.append(json.loads(output.strip().splitlines()[-1]))
    return results


def main_per_ur_type(argv, doc, script, section, bench, table, seconds, cases=('ur3', 'ur5e')):
    """A benchmark's main() that measures each of `cases` (by default a ur3, CB3 at 125 Hz, and a ur5e,
    e-Series at 500 Hz), each in a process and on a master of its own: bench(case, seconds, rospy) -> a
    JSON-able result, table(results) -> Markdown, written into `section` of --output."""
    import argparse
    parser = argparse.ArgumentParser(description=doc.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=seconds, help='measuring window (s, default %g)' % seconds)
    parser.add_argument('--output', help='RESULTS.md to write the section "%s" into' % section)
    parser.add_argument('--one', help=argparse.SUPPRESS)  # internal: measure one ur_type, print JSON
    args = parser.parse_args(argv)
    name = os.path.splitext(os.path.basename(script))[0]
    if args.one:
        return measure_alone(name + '_bench', lambda rospy: bench(args.one, args.seconds, rospy))

    def say(text):
        print('[%s bench] %s' % (name, text), file=sys.stderr)
    say('%s: %g s each' % (', '.join(cases), args.seconds))
    results = measure_each(os.path.abspath(script), cases, ['--seconds', str(args.seconds)], say)
    if results is None:
        return 1
    text = table(results)
    print(text)
    if args.output:
        replace_section(args.output, section, text)
    return 0
