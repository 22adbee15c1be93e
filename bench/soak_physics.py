"""Soak of the physics cell (bench/soak.py --what physics): the bring-up with sim:=true physics:=true, driven for a long time.

Through the real drivers' interfaces only, the shipped examples in a loop:
pick and weigh (the default world's block, where it now stands, from the
cell's truth: up, weighed, put back, opened),
then the guarded touch (down onto the table until 10 N, back off, back to the
trajectory controller). Limits: the resident memory of the arm's process
(where the cell steps), of the FT 300's and of the gripper's grows by at
most 5 MB each after the warm-up; every cycle succeeds and weighs the block
within 2 % of its world-file mass. With --wire (bench/soak_wire.py), the FT 300 and the 2F-140 are also
on their serial lines, read by clients that reconnect every --reconnect s: each stream session must be the
topic's readings frame for message, and every status read of the gripper must be answered.
"""
import math
import os
import tempfile
import time

import numpy as np
from transforms3d.euler import quat2euler

import benchlib
from ur3_ft_gripper_description.devices.physics import link
from ur3_ft_gripper_testing import shipped

# The examples, as shipped.
guarded_touch = shipped.script('examples/guarded_touch.py')
pick_and_weigh = shipped.script('examples/pick_and_weigh.py')

RSS_LIMIT_MB = 5.0
WEIGHT_TOLERANCE = 0.02
# The guarded touch's speed (m/s): at full speed the cell runs on while the touch reacts, so it presses
# slowly enough that a late reaction stays far below the protective stop.
TOUCH_SPEED = 0.005
NODES = ('/ur_hardware_interface', '/robotiq_ft_sensor', '/robotiq2FGripper')


def block_pose(truth):
    """(x, y, yaw) of the block in the cell, from the link's truth (m, rad)."""
    position, quaternion = truth.truth()[1]['objects']['block']
    return position[0], position[1], quat2euler(quaternion, axes='sxyz')[2]


def run(args, seconds, record_section):
    """The soak; exit status 0 when every limit holds. Writes its section into args.record if given."""
    load_before = benchlib.load_average()
    master = benchlib.use_new_master()
    launch = None
    problems, rss, cycles, weights, cpu, simulated = [], {}, 0, [], None, 0.0
    wire, published, wire_rows = None, [], []
    lines = {name: os.path.join(tempfile.gettempdir(), 'tty%s-soak-%d' % (name, os.getpid()))
             for name in ('RobotiqFT300', 'Robotiq2F')}
    try:
        import rospy
        launch = benchlib.roslaunch('ur3_ft_gripper_description', 'ur3_ft_gripper_bringup.launch', 'sim:=true',
                                    'physics:=true', 'real_time_factor:=%g' % args.real_time_factor,
                                    *(['sim_ft_serial_port:=' + lines['RobotiqFT300'],
                                       'sim_gripper_serial_port:=' + lines['Robotiq2F']] if args.wire else []),
                                    log=os.environ.get('SOAK_LOG'))
        # The bring-up sets use_sim_time; this node must start on the same clock as the cell.
        import rosgraph
        benchlib.wait_for(lambda: rosgraph.Master('/soak_physics').hasParam('/use_sim_time'),
                          'the bring-up to set /use_sim_time', 60)
        rospy.init_node('soak_physics', disable_signals=True)
        quiet = lambda text: None  # noqa: E731
        picker = pick_and_weigh.PickAndWeigh(rospy, say=quiet)
        toucher = guarded_touch.GuardedTouch(rospy, say=quiet)
        x0, y0, top, yaw0, _, mass = pick_and_weigh.target_of(pick_and_weigh.default_world_file(), 'block')
        # Each put-down leaves the block a little away from where it was picked, as on a real table; the
        # soak picks it where it now stands (the cell's own truth: a camera's job on a real cell), so the
        # shift adds up in the report, not in a gripper landing on the block after a few dozen cycles.
        truth = link.CellClient(link.node_cell_address(rospy)[0])
        first = block_pose(truth)
        shifts = []
        pids = {node: benchlib.node_pid(node) for node in NODES}
        if args.wire:
            import soak_wire
            from geometry_msgs.msg import WrenchStamped
            # Every reading the FT 300 publishes, in the stream's counts, to hold each session's frames against.
            rospy.Subscriber('robotiq_ft_wrench', WrenchStamped,
                             lambda msg: published.append((msg.header.stamp, soak_wire.counts(msg))), queue_size=None)
            wire = soak_wire.WireClients(lines['RobotiqFT300'], lines['Robotiq2F'], args.reconnect)
            wire.start()
        start = time.monotonic()
        warm = None
        while time.monotonic() - start < args.warmup + seconds:
            try:
                before = block_pose(truth)
                x, y = x0 + before[0] - first[0], y0 + before[1] - first[1]
                picker.pick(x, y, top, yaw0 + before[2] - first[2])
                weighed, _ = picker.weigh()
                picker.put_down()
                shifts.append(math.hypot(*(np.subtract(block_pose(truth)[:2], before[:2]))))
                toucher.start(*guarded_touch.START_XY)
                toucher.touch(TOUCH_SPEED, 10.0, timeout=60.0)
                toucher.back_off(TOUCH_SPEED)
                weights.append(weighed)
                if abs(weighed - mass) > WEIGHT_TOLERANCE * mass:
                    problems.append('cycle %d: weighed %.4f kg, not %.4f' % (cycles, weighed, mass))
            except Exception as exc:  # a cycle that failed is a finding, the soak goes on
                problems.append('cycle %d: %s' % (cycles, ' '.join(str(exc).split())))
            cycles += 1
            now = time.monotonic()
            if warm is None and now - start >= args.warmup:
                warm = (now, {n: benchlib.cpu_seconds(p) for n, p in pids.items()}, cycles, len(problems),
                        truth.truth()[0])
                rss = {n: [benchlib.rss_mb(p)] for n, p in pids.items()}
            elif warm is not None:
                for n, p in pids.items():
                    rss[n].append(benchlib.rss_mb(p))
        if warm is None:
            raise RuntimeError('the run ended within the warm-up: give more time than --warmup')
        wall = time.monotonic() - warm[0]
        cpu = {n: 100.0 * (benchlib.cpu_seconds(p) - warm[1][n]) / wall for n, p in pids.items()}
        simulated = truth.truth()[0] - warm[4]
        measured_cycles = cycles - warm[2]
        if wire is not None:
            wire.stop()
            wire_rows, wire_problems = wire.judge([value for _, value in sorted(published)])
            problems += wire_problems
    finally:
        benchlib.stop(launch)
        benchlib.stop(master)
    rows = ['| measured | %.0f s after %.0f s warm-up; %d cycles (%d in the warm-up) |' % (
        seconds, args.warmup, measured_cycles, cycles - measured_cycles),
        '| each cycle | examples/pick_and_weigh.py on the default world\'s block, then examples/guarded_touch.py |',
        '| the block\'s shift on the table per pick and put-down: mean, max; in all | %.2f, %.2f mm; %.1f mm |' % (
            1e3 * np.mean(shifts or [float('nan')]), 1e3 * max(shifts or [float('nan')]), 1e3 * sum(shifts)),
        '| block weighed (world file: 0.3 kg): min, max over %d cycles | %.4f, %.4f kg |' % (
            len(weights), min(weights or [float('nan')]), max(weights or [float('nan')]))]
    for n in NODES:
        growth = max(rss[n]) - rss[n][0]
        if growth > RSS_LIMIT_MB:
            problems.append('%s resident memory grew by %.1f MB (limit %g)' % (n, growth, RSS_LIMIT_MB))
        rows.append('| %s resident memory: after warm-up, max, end, growth | %.1f, %.1f, %.1f MB, +%.2f MB '
                    '(limit %g MB) |' % (n, rss[n][0], max(rss[n]), rss[n][-1], growth, RSS_LIMIT_MB))
    rows.append('| CPU, mean over the measurement (%% of one core): ur_hardware_interface (arm + cell, 125 Hz), '
                'robotiq_ft_sensor, robotiq2FGripper | %.0f, %.0f, %.0f |' % tuple(cpu[n] for n in NODES))
    rows += wire_rows
    rows.append('| cycles that failed, and other findings | %d |' % len(problems))
    return benchlib.report_soak(
        args.record, record_section,
        '## Soak of the physics cell%s (`bash tools/quickstart soak --what physics%s`)'
        % ((' with its devices on the wire', ' --wire') if args.wire else ('', '')),
        'ur3_ft_gripper_bringup.launch sim:=true physics:=true real_time_factor:=%g (default world, on the cell\'s '
        'simulated clock; simulated seconds over the wall clock\'s: %.2f) on its own master, driven through the '
        'real drivers\' interfaces only; the guarded touch at %g mm/s.'
        % (args.real_time_factor, simulated / max(seconds, 1e-9), 1e3 * TOUCH_SPEED),
        load_before, rows, problems, 'soak (physics)')
