#!/usr/bin/env python3
"""Benchmarks of this package side by side with upstream ur_description, in one run.

    python3 bench/benchmarks.py [--short] [--output bench/RESULTS.md]

Prints the tables and ratios and writes them into the "bench" section of
RESULTS.md (one section per robotiq variant) with the machine, date and load.
`bash bench/run` (= `tools/quickstart bench`; UR3_FT_GRIPPER_ROBOTIQ=kinetic for the other variant) runs it
in the workspace. Measurements, not pass/fail: the exit status is 0 when every
benchmark ran. --short runs each a few times only (CI keeps the script working).
"""
import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time
import xml.dom.minidom

import benchlib  # this folder is the script's, first on sys.path

PACKAGE = 'ur3_ft_gripper_description'
GOALS = {'expansion': 1.25, 'bringup': 1.15}


# -- xacro: the ROS package, as upstream's load_ur.launch runs it ----------------

def xacro_setup():
    """(xacro executable, environment for roslaunch, description) for both models."""
    import rospkg
    from catkin_pkg.package import parse_package
    from roslaunch.substitution_args import resolve_args
    path = resolve_args('$(find xacro)/xacro')  # what upstream's load_ur.launch runs
    # package.xml's version, read without rospkg's manifest, which asks rosdep and
    # says its database is empty on a machine that never needed one.
    version = parse_package(rospkg.RosPack().get_path('xacro')).version
    return path, dict(os.environ), 'xacro %s (%s)' % (version, path)


def upstream_xacro_file():
    import rospkg
    return os.path.join(rospkg.RosPack().get_path('ur_description'), 'urdf', 'ur3.xacro')


def our_xacro_file():
    return os.path.join(benchlib.PACKAGE_DIR, 'urdf', 'ur3_ft_gripper.xacro')


# -- model expansion ------------------------------------------------------------

def time_command(argv, env):
    start = time.monotonic()
    run = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env,
                         universal_newlines=True)
    elapsed = time.monotonic() - start
    if run.returncode != 0:
        raise RuntimeError('%s failed: %s' % (' '.join(argv), run.stderr.strip()[-500:]))
    return elapsed, run.stdout


def bench_expansion(xacro, env, runs):
    commands = {
        'upstream': [xacro, upstream_xacro_file()],
        'ours': [xacro, our_xacro_file()],
        'ours_users': [sys.executable, os.path.join(benchlib.PACKAGE_DIR, 'scripts', 'expand_description')],
    }
    times = {k: [] for k in commands}
    outputs = {}
    for _ in range(runs):  # interleaved, so that a load change hits all alike
        for key, argv in commands.items():
            elapsed, outputs[key] = time_command(argv, env)
            times[key].append(elapsed)
    return times, outputs


def links_of(urdf):
    doc = xml.dom.minidom.parseString(urdf)
    return [e.getAttribute('name') for e in doc.documentElement.childNodes
            if e.nodeType == e.ELEMENT_NODE and e.tagName == 'link']


# -- bring-up ---------------------------------------------------------------------

def bench_bringup(load_launch, links, env, runs, rospy, tf2_ros, timeout=60.0):
    """Seconds from starting roslaunch until TF has every link of the model; None if never."""
    times = []
    root = links[0]
    for _ in range(runs):
        buffer = tf2_ros.Buffer()
        listener = tf2_ros.TransformListener(buffer)
        start = time.monotonic()
        launch = benchlib.roslaunch(os.path.join(benchlib.BENCH_DIR, 'bringup.launch'),
                                    'load:=%s' % load_launch, env=env)
        try:
            def all_frames():
                return all(buffer.can_transform(root, link, rospy.Time(0)) for link in links)
            end = start + timeout
            done = None
            while time.monotonic() < end and launch.poll() is None:
                if all_frames():
                    done = time.monotonic() - start
                    break
                time.sleep(0.005)
        finally:
            benchlib.stop(launch)
            listener.unregister()
        times.append(done)
        if done is None:
            return None
    return times


# -- ft300_sim (node robotiq_ft_sensor) ---------------------------------------------

class Received(object):
    def __init__(self):
        self.lock = threading.Lock()
        self.items = []

    def add(self, msg):
        received = time.monotonic()
        with self.lock:
            self.items.append((received, msg))

    def since(self, t):
        with self.lock:
            return [(r, m) for r, m in self.items if r >= t]

    def last(self):
        with self.lock:
            return self.items[-1][1] if self.items else None


def gaps(values):
    return [b - a for a, b in zip(values, values[1:])]


# (~rate, subscribe to both topics): at 100 Hz also the wrench alone, what the
# single-topic node published, so that one run compares the two.
# (rate, both topics subscribed, its serial line streaming to a reader beside them)
FT300_RUNS = ((100, False, False), (100, True, False), (100, True, True), (500, True, False), (1000, True, False))
# rq_sensor's start of the data stream (write 0x0200 to register 410), and the stop.
START_STREAM = bytes.fromhex('09 10 01 9A 00 01 02 02 00 CD CA')
STOP_STREAM = b'\xff' * 50


class SerialReader(object):
    """A client of a device's serial line (the pseudo-terminal's path): writes `request`, then reads and
    counts what comes, in a thread, until stop()."""

    def __init__(self, path, baudrate, request, every=None):
        import serial
        benchlib.wait_for(lambda: os.path.exists(path), 'the serial line at %s' % path, 30)
        self.port = serial.Serial(path, baudrate, timeout=min(0.05, every or 0.05) / 4)
        self.request, self.every, self.received = request, every, 0
        self.stopping = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        self.port.write(self.request)
        next_request = time.monotonic() + (self.every or 0.0)
        while not self.stopping.is_set():
            self.received += len(self.port.read(4096))
            if self.every and time.monotonic() >= next_request:
                self.port.write(self.request)
                next_request += self.every

    def stop(self, last=b''):
        self.stopping.set()
        self.thread.join()
        self.port.write(last)
        self.port.close()


def bench_ft300(rate, seconds, rospy, both=True, serial=False):
    """Rate, gaps and CPU of ft300_sim; `both`: a subscriber on robotiq_ft_sensor too, not only the wrench;
    `serial`: its serial line too, streaming to a reader as rq_sensor starts it."""
    from geometry_msgs.msg import WrenchStamped
    from robotiq_ft_sensor.msg import ft_sensor
    name = 'ft300_bench_%d_%s%s' % (rate, 'both' if both else 'wrench', '_serial' if serial else '')
    path = os.path.join(tempfile.gettempdir(), 'ttyFT300-%s-%d' % (name, os.getpid()))
    wrench, stream = Received(), Received()
    subscribers = [rospy.Subscriber('%s/robotiq_ft_wrench' % name, WrenchStamped, wrench.add,
                                    queue_size=10000, tcp_nodelay=True)]
    if both:
        subscribers.append(rospy.Subscriber('%s/robotiq_ft_sensor' % name, ft_sensor, stream.add,
                                            queue_size=10000, tcp_nodelay=True))
    process = benchlib.node('ft300_sim', '__name:=robotiq_ft_sensor', '__ns:=/%s' % name,
                            '_rate:=%g' % rate, *(['_modbus_rtu_port:=' + path] if serial else []))
    reader = None
    try:
        benchlib.wait_for(lambda: wrench.last() and (stream.last() or not both),
                          'ft300_sim at %g Hz on %s' % (rate, 'both topics' if both else 'the wrench'), 30)
        if serial:
            reader = SerialReader(path, 19200, START_STREAM)
        time.sleep(1.0)  # warm-up
        cpu0, t0, bytes0 = benchlib.cpu_seconds(process.pid), time.monotonic(), reader.received if reader else 0
        time.sleep(seconds)
        cpu1, t1, bytes1 = benchlib.cpu_seconds(process.pid), time.monotonic(), reader.received if reader else 0
    finally:
        if reader is not None:
            reader.stop(STOP_STREAM)
        benchlib.stop(process)
        for subscriber in subscribers:
            subscriber.unregister()
    window = [(r, m) for r, m in wrench.since(t0) if r <= t1]
    stamps = [m.header.stamp.to_sec() for _, m in window]
    # ft_sensor has no header: its gaps are as received.
    stream_window = [r for r, _ in stream.since(t0) if r <= t1]
    return dict(rate=rate, both=both, serial=serial, frames=(bytes1 - bytes0) / 16.0 / (t1 - t0) if serial else None,
                achieved=len(window) / (t1 - t0),
                achieved_stream=len(stream_window) / (t1 - t0) if both else None,
                p99_stamp=benchlib.percentile(gaps(stamps), 99),
                p99_received=benchlib.percentile(gaps([r for r, _ in window]), 99),
                p99_stream=benchlib.percentile(gaps(stream_window), 99) if both else None,
                max_stamp=max(gaps(stamps)), cpu=100.0 * (cpu1 - cpu0) / (t1 - t0))


# -- gripper_sim (node robotiq2FGripper) ----------------------------------------------

def bench_gripper(commands, rospy):
    """Seconds from publishing a register command to the first status whose gPO moves toward it."""
    from robotiq_2f_gripper_control.msg import (Robotiq2FGripper_robot_input,
                                                Robotiq2FGripper_robot_output)

    def command(position):
        return Robotiq2FGripper_robot_output(rACT=1, rGTO=1, rPR=position, rSP=255, rFR=150)

    def settled_at(position):
        s = received.last()
        return s is not None and s.gSTA == 3 and s.gOBJ == 3 and s.gPO == position

    received = Received()
    subscriber = rospy.Subscriber('Robotiq2FGripperRobotInput', Robotiq2FGripper_robot_input,
                                  received.add, queue_size=1000, tcp_nodelay=True)
    publisher = rospy.Publisher('Robotiq2FGripperRobotOutput', Robotiq2FGripper_robot_output,
                                queue_size=10, tcp_nodelay=True)
    process = benchlib.node('gripper_sim', '__name:=robotiq2FGripper')
    latencies = []
    try:
        benchlib.wait_for(lambda: received.last() and publisher.get_num_connections(), 'gripper_sim', 30)
        publisher.publish(command(100))  # activate (1.5 s), then move to 100
        benchlib.wait_for(lambda: settled_at(100), 'the gripper activated at gPO 100', 30)
        for i in range(commands):
            # 20 counts (12 mm) each way, closing and opening in turn.
            target = 120 if i % 2 == 0 else 100
            closing = target > received.last().gPO
            time.sleep(0.0123 * (i % 7) / 7)  # spread the commands over the publish period
            before = received.last().gPO
            sent = time.monotonic()
            publisher.publish(command(target))
            first = None
            end = sent + 2.0
            while first is None and time.monotonic() < end:
                for r, msg in received.since(sent):
                    if (msg.gPO > before) if closing else (msg.gPO < before):
                        first = r
                        break
                time.sleep(0.001)
            if first is None:
                raise RuntimeError('gripper_sim did not move toward gPO %d within 2 s' % target)
            latencies.append(first - sent)
            benchlib.wait_for(lambda: settled_at(target), 'the gripper at gPO %d' % target, 10, step=0.01)
    finally:
        benchlib.stop(process)
        subscriber.unregister()
        publisher.unregister()
    return latencies


# Robotiq's node's status read (function 3, three registers at 0x07D0, slave 9) and its reply's length.
READ_GRIPPER_STATUS = bytes.fromhex('09 03 07 D0 00 03 04 0E')
GRIPPER_REPLY_BYTES = 11


def bench_gripper_cpu(seconds, rospy):
    """CPU of gripper_sim (% of a core) with its Modbus RTU line idle, and with a client reading the status at
    50 Hz; and the replies it got a second."""
    path = os.path.join(tempfile.gettempdir(), 'ttyRobotiq2F-bench-%d' % os.getpid())
    process = benchlib.node('gripper_sim', '__name:=robotiq2FGripper', '__ns:=/gripper_cpu_bench',
                            '_modbus_rtu_port:=' + path)
    try:
        benchlib.wait_for(lambda: os.path.exists(path), 'gripper_sim\'s serial line', 30)
        time.sleep(1.0)
        cpu0, t0 = benchlib.cpu_seconds(process.pid), time.monotonic()
        time.sleep(seconds)
        idle = 100.0 * (benchlib.cpu_seconds(process.pid) - cpu0) / (time.monotonic() - t0)
        reader = SerialReader(path, 115200, READ_GRIPPER_STATUS, every=0.02)
        time.sleep(1.0)
        cpu0, t0, bytes0 = benchlib.cpu_seconds(process.pid), time.monotonic(), reader.received
        time.sleep(seconds)
        cpu1, t1, bytes1 = benchlib.cpu_seconds(process.pid), time.monotonic(), reader.received
        reader.stop()
    finally:
        benchlib.stop(process)
    return dict(idle=idle, modbus=100.0 * (cpu1 - cpu0) / (t1 - t0),
                replies=(bytes1 - bytes0) / float(GRIPPER_REPLY_BYTES) / (t1 - t0))


# -- report -------------------------------------------------------------------------

def ms(seconds):
    return '%.0f' % (1e3 * seconds) if seconds is not None else 'n/a'


def report(r):
    exp, bring, short = r['expansion'], r['bringup'], r['short']
    up, ours, users = (benchlib.median(exp[k]) for k in ('upstream', 'ours', 'ours_users'))
    lines = [
        '%s; %s; load average before / after: %s / %s; robotiq-%s; %s%s.' % (
            r['date'], r['machine'], r['load_before'], r['load_after'], r['variant'], r['xacro'],
            '; SHORT run (CI), not for comparison' if short else ''),
        '',
        '### Model expansion (median of %d runs each, wall time of the whole command)' % len(exp['upstream']),
        '',
        '| model | command | median ms | min ms | ratio to upstream | goal |',
        '| --- | --- | ---: | ---: | ---: | --- |',
        '| upstream `ur_description/urdf/ur3.xacro` (%d links) | xacro | %s | %s | 1.00 | |' % (
            r['links_upstream'], ms(up), ms(min(exp['upstream']))),
        '| ours `urdf/ur3_ft_gripper.xacro` (%d links) | the same xacro | %s | %s | **%.2f** | <= %.2f: %s |' % (
            r['links_ours'], ms(ours), ms(min(exp['ours'])), ours / up, GOALS['expansion'],
            'met' if ours / up <= GOALS['expansion'] else 'NOT met'),
        '| ours, what users run | `expand_description` | %s | %s | %.2f | |' % (
            ms(users), ms(min(exp['ours_users'])), users / up),
        '',
    ]
    b_up = benchlib.median(bring['upstream']) if bring['upstream'] else None
    rows = [('upstream `load_ur3.launch`', bring['upstream'], None)]
    rows.append(('ours `load_ur3_ft_gripper.launch` (`expand_description`, what users run)',
                 bring['ours'], GOALS['bringup']))
    rows.append(('ours, same xacro as upstream (`bench/load_plain_xacro.launch`)', bring['ours_plain'], None))
    lines += [
        '### Bring-up (roslaunch start until every link is in TF; load launch + joint_state_publisher '
        '+ robot_state_publisher, headless; median of %d runs)' % r['bringup_runs'],
        '',
        '| launch | median ms | min ms | ratio to upstream | goal |',
        '| --- | ---: | ---: | ---: | --- |',
    ]
    for label, times, goal in rows:
        if not times:
            lines.append('| %s | n/a | n/a | n/a | %s |' % (
                label, 'robot_state_publisher refuses the plain result (second base_link of the '
                'jr-robotics fork)' if goal is None and label.startswith('ours') else ''))
            continue
        med = benchlib.median(times)
        ratio = med / b_up
        goal_text = ''
        if goal:
            goal_text = '<= %.2f: %s' % (goal, 'met' if ratio <= goal else 'NOT met')
        lines.append('| %s | %s | %s | %s | %s |' % (
            label, ms(med), ms(min(times)), '%.2f' % ratio if label.startswith('ours') else '1.00',
            goal_text))
    lines += [
        '',
        '### ft300_sim, node robotiq_ft_sensor (TF from robot_state_publisher at 50 Hz; %g s per run '
        'after 1 s warm-up)' % r['ft_seconds'],
        '',
        'It publishes robotiq_ft_wrench and robotiq_ft_sensor every cycle; "subscribed" says which of '
        'them this benchmark receives (a topic without a subscriber is not serialized or sent).',
        '',
        '| ~rate Hz | subscribed | achieved Hz wrench / ft_sensor | p99 gap ms wrench (stamps) '
        '| p99 gap ms received wrench / ft_sensor | max gap ms wrench (stamps) | CPU % of one core | goal |',
        '| ---: | --- | ---: | ---: | ---: | ---: | ---: | --- |',
    ]
    for f in r['ft300']:
        goal = ''
        if f['rate'] == 100 and f.get('serial'):
            ok = f['p99_stamp'] < 0.012 and f['cpu'] < 10.0
            goal = 'p99 < 12 ms, CPU < 10 %%: %s' % ('met' if ok else 'NOT met')
        elif f['rate'] == 100:
            ok = f['p99_stamp'] < 0.012 and f['cpu'] < 5.0
            goal = 'p99 < 12 ms, CPU < 5 %%: %s' % ('met' if ok else 'NOT met')
        elif f['rate'] == 1000:
            goal = 'sustained: %s' % ('met' if f['achieved'] >= 0.95 * 1000 else 'NOT met')
        both = f['both']
        lines.append('| %d | %s | %.1f / %s | %.1f | %.1f / %s | %.1f | %.1f | %s |' % (
            f['rate'], ('both + serial stream (%.1f frames/s)' % f['frames'] if f.get('serial') else 'both')
            if both else 'wrench only', f['achieved'],
            '%.1f' % f['achieved_stream'] if both else '-', 1e3 * f['p99_stamp'],
            1e3 * f['p99_received'], '%.1f' % (1e3 * f['p99_stream']) if both else '-',
            1e3 * f['max_stamp'], f['cpu'], goal))
    lat = r['gripper']
    lines += [
        '',
        '### gripper_sim, node robotiq2FGripper (~rate 50 Hz: period 20 ms; %d commands, rPR 100 <-> 120 '
        'at rSP 255)' % len(lat),
        '',
        '| Robotiq2FGripperRobotOutput -> first Robotiq2FGripperRobotInput whose gPO moves toward rPR '
        '| median ms | p95 ms | max ms | goal |',
        '| --- | ---: | ---: | ---: | --- |',
        '| latency | %.1f | %.1f | %.1f | < 40 ms (two periods): %s |' % (
            1e3 * benchlib.median(lat), 1e3 * benchlib.percentile(lat, 95), 1e3 * max(lat),
            'met' if benchlib.percentile(lat, 95) < 0.040 else 'NOT met (p95)'),
    ]
    cpu = r.get('gripper_cpu')
    if cpu:
        lines += [
            '',
            '### gripper_sim with its Modbus RTU line (%g s each, after 1 s warm-up; a client reading the status '
            'at 50 Hz as Robotiq\'s node polls it, beside none)' % r['ft_seconds'],
            '',
            '| CPU % of one core, no client | with the Modbus RTU client | ratio | replies/s | goal |',
            '| ---: | ---: | ---: | ---: | --- |',
            '| %.1f | %.1f | %.2f | %.1f | < 10 %%: %s |' % (
                cpu['idle'], cpu['modbus'], cpu['modbus'] / cpu['idle'] if cpu['idle'] else float('nan'),
                cpu['replies'], 'met' if cpu['modbus'] < 10.0 else 'NOT met'),
        ]
    return '\n'.join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--short', action='store_true', help='few runs, for CI')
    parser.add_argument('--output', default=os.path.join(benchlib.BENCH_DIR, 'RESULTS.md'),
                        help='RESULTS.md to write the bench section into')
    args = parser.parse_args(argv)
    runs = 2 if args.short else 10
    results = dict(short=args.short, date=benchlib.now_text(), machine=benchlib.machine(),
                   load_before=benchlib.load_average(), variant=os.environ.get('ROBOTIQ_VARIANT', '?'))
    xacro, env, results['xacro'] = xacro_setup()
    say('model expansion, %d runs each' % runs)
    results['expansion'], outputs = bench_expansion(xacro, env, runs)
    results['links_upstream'] = len(links_of(outputs['upstream']))
    results['links_ours'] = len(links_of(outputs['ours_users']))

    master = benchlib.use_new_master()
    env['ROS_MASTER_URI'] = os.environ['ROS_MASTER_URI']
    try:
        import rospy
        import tf2_ros
        rospy.init_node('bench', disable_signals=True)
        import rospkg
        up_launch = os.path.join(rospkg.RosPack().get_path('ur_description'), 'launch', 'load_ur3.launch')
        our_launch = os.path.join(benchlib.PACKAGE_DIR, 'launch', 'load_ur3_ft_gripper.launch')
        plain_launch = os.path.join(benchlib.BENCH_DIR, 'load_plain_xacro.launch')
        results['bringup_runs'] = 1 if args.short else 10
        say('bring-up, %d runs each' % results['bringup_runs'])
        up_links, our_links = links_of(outputs['upstream']), links_of(outputs['ours_users'])
        results['bringup'] = {k: [] for k in ('upstream', 'ours', 'ours_plain')}
        for _ in range(results['bringup_runs']):  # interleaved, like the expansion
            for key, launch, links in (('upstream', up_launch, up_links), ('ours', our_launch, our_links),
                                       ('ours_plain', plain_launch, our_links)):
                if results['bringup'][key] is None:
                    continue
                got = bench_bringup(launch, links, env, 1, rospy, tf2_ros,
                                    timeout=15.0 if key == 'ours_plain' else 60.0)
                if got is None and key != 'ours_plain':
                    raise RuntimeError('%s: the model never completed in TF' % launch)
                results['bringup'][key] = None if got is None else results['bringup'][key] + got

        # The simulated devices against our model in TF, as in the view launch. The bring-ups
        # above left their robot_description on the master: gone first, so that the wait below
        # is for ours and ft300_sim does not read the bare arm of the last one.
        if rospy.has_param('robot_description'):
            rospy.delete_param('robot_description')
        launch = benchlib.roslaunch(os.path.join(benchlib.BENCH_DIR, 'bringup.launch'),
                                    'load:=%s' % our_launch, env=env)
        try:
            benchlib.wait_for(lambda: rospy.has_param('robot_description'), 'robot_description', 60)
            results['ft_seconds'] = 2.0 if args.short else 10.0
            results['ft300'] = []
            for rate, both, serial in FT300_RUNS:
                say('ft300_sim at %d Hz, %s%s' % (rate, 'both topics' if both else 'wrench only',
                                                  ' and its serial stream' if serial else ''))
                results['ft300'].append(bench_ft300(rate, results['ft_seconds'], rospy, both, serial))
            say('gripper_sim CPU, without and with a Modbus RTU client')
            results['gripper_cpu'] = bench_gripper_cpu(results['ft_seconds'], rospy)
            say('gripper_sim latency')
            results['gripper'] = bench_gripper(6 if args.short else 40, rospy)
        finally:
            benchlib.stop(launch)
    finally:
        benchlib.stop(master)
    results['load_after'] = benchlib.load_average()
    text = report(results)
    print(text)
    # One section per robotiq variant: with robotiq-kinetic the plain-xacro bring-up row exists too.
    benchlib.replace_section(args.output, 'bench robotiq-%s' % results['variant'],
                             '## Benchmarks with robotiq-%s (`bash bench/run%s`)\n\n%s' % (
                                 results['variant'], ' --short' if args.short else '', text))
    say('written to %s' % args.output)
    return 0


def say(text):
    print('[bench] %s' % text, file=sys.stderr, flush=True)


if __name__ == '__main__':
    sys.exit(main())
