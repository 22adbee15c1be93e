#!/usr/bin/env python3
"""The controller's network faces, no ROS: the arm's control cycle with clients connected, beside none.

    python3 bench/network_faces.py [--seconds 2] [--runs 5] [--output bench/RESULTS.md]

In the sourced workspace (tools/quickstart shell). The arm's core (ArmCore,
kinematic joints) of a ur3 (8 ms cycles) and a ur5e (2 ms) with its network
faces on free loopback ports, each cycle handed to the faces as the arm's node
hands it (NetworkFaces.after_cycle), in three cases:
- no client: the faces listen, nobody is connected;
- RTDE: one client reading the 37 fields ur_rtde's RTDEReceiveInterface asks
  for by default, at the controller's rate;
- every stream: that RTDE client, a real-time interface client (a package each
  cycle) and a primary interface client (a robot state each 0.1 s).
The clients read in a process of their own. CPU time of this process (the
control cycle and the faces' sending threads) per control cycle, in chunks of
`seconds` of simulated time, the cases interleaved; median over `runs`, and
each case over no client. Figures, not pass/fail.
"""
import argparse
import multiprocessing
import socket
import struct
import sys
import threading
import time

import benchlib  # this folder is the script's, first on sys.path

CASES = ('no client', 'RTDE', 'every stream')
UR_TYPES = (('ur3', 125.0), ('ur5e', 500.0))
# ur_rtde 1.6.5's RTDEReceiveInterface default recipe (its source), without the version-dependent ones.
RTDE_FIELDS = [
    'timestamp', 'target_q', 'target_qd', 'target_qdd', 'target_current', 'target_moment', 'actual_q', 'actual_qd',
    'actual_current', 'joint_control_output', 'actual_TCP_pose', 'actual_TCP_speed', 'actual_TCP_force',
    'target_TCP_pose', 'target_TCP_speed', 'actual_digital_input_bits', 'joint_temperatures',
    'actual_execution_time', 'robot_mode', 'joint_mode', 'safety_mode', 'actual_tool_accelerometer', 'speed_scaling',
    'target_speed_fraction', 'actual_momentum', 'actual_main_voltage', 'actual_robot_voltage',
    'actual_robot_current', 'actual_joint_voltage', 'actual_digital_output_bits', 'runtime_state',
    'standard_analog_input0', 'standard_analog_input1', 'standard_analog_output0', 'standard_analog_output1',
    'robot_status_bits', 'safety_status_bits']


def say(text):
    print('[network_faces bench] %s' % text, file=sys.stderr)


def new_cell(ur_type, loop_hz):
    """(core, faces, dt): the kinematic core of `ur_type` with its faces listening on free loopback ports,
    as ur_controller_sim builds them."""
    from ur3_ft_gripper_description.devices.ur_arm.controller_sim import build
    from ur3_ft_gripper_description.devices.ur_arm.network_faces import PORTS
    core, faces, _ = build(ur_type, '127.0.0.1', log=say, ports={name: 0 for name in PORTS})
    faces.start()
    return core, faces, 1.0 / loop_hz


def read_forever(sock):
    while sock.recv(1 << 16):
        pass


def clients(ports, rate, streams, ready):
    """The clients' process: an RTDE client (the recipe at `rate`), and the other `streams` read and dropped."""
    rtde = socket.create_connection(('127.0.0.1', ports['rtde']))

    def ask(kind, payload=b''):
        rtde.sendall(struct.pack('>HB', len(payload) + 3, ord(kind)) + payload)
        size, = struct.unpack('>H', rtde.recv(2, socket.MSG_WAITALL))
        return rtde.recv(size - 2, socket.MSG_WAITALL)

    ask('V', struct.pack('>H', 2))
    ask('O', struct.pack('>d', rate) + ','.join(RTDE_FIELDS).encode())
    ask('S')
    sockets = [rtde] + [socket.create_connection(('127.0.0.1', ports[name])) for name in streams]
    for sock in sockets:
        threading.Thread(target=read_forever, args=(sock,), daemon=True).start()
    ready.set()
    time.sleep(3600)


def per_cycle(core, faces, dt, seconds):
    """CPU seconds of this process per control cycle over `seconds` of simulated time."""
    cycles = int(round(seconds / dt))
    began = time.process_time()
    for _ in range(cycles):
        faces.after_cycle(dt, core.step(dt))
    return (time.process_time() - began) / cycles


def bench(seconds, runs):
    results = []
    for ur_type, loop_hz in UR_TYPES:
        cells = {case: new_cell(ur_type, loop_hz) for case in CASES}
        processes = []
        for case, streams in (('RTDE', ()), ('every stream', ('realtime', 'primary'))):
            core, faces, dt = cells[case]
            ready = multiprocessing.Event()
            process = multiprocessing.Process(target=clients, daemon=True, args=(
                {name: faces.port(name) for name in ('rtde', 'realtime', 'primary')}, loop_hz, streams, ready))
            process.start()
            processes.append(process)
            if not ready.wait(60):
                raise RuntimeError('the clients did not connect within 60 s')
        time.sleep(0.5)  # the faces' threads take the connections in
        for case in CASES:
            per_cycle(*cells[case], 1.0)
        measured = {case: [] for case in CASES}
        for _ in range(runs):
            for case in CASES:
                measured[case].append(per_cycle(*cells[case], seconds))
        for process in processes:
            process.terminate()
        for core, faces, dt in cells.values():
            faces.shutdown()
        say('%s: %s' % (ur_type, ', '.join('%s %.0f us' % (case, 1e6 * benchlib.median(measured[case]))
                                            for case in CASES)))
        results.append((ur_type, loop_hz, measured))
    return results


def section(results, seconds, runs, load):
    lines = [
        '### The controller\'s network faces (`bench/network_faces.py`, no ROS), %s' % benchlib.now_text(),
        '',
        'Machine: %s; load average before: %s. ArmCore.step (kinematic joints) and the faces\' share of each '
        'cycle, with no client, with one RTDE client reading ur_rtde\'s 37 default fields at the controller\'s '
        'rate, and with that client, a real-time interface client and a primary interface client; CPU time of '
        'the process per control cycle (the sending threads included, the clients in a process of their own); '
        '%d runs of %g s of simulated time each, interleaved; median (range), and over no client.'
        % (benchlib.machine(), load, runs, seconds),
        '',
        '| ur_type | period | no client (us a cycle) | RTDE (us a cycle) | every stream (us a cycle) | RTDE / none '
        '| every stream / none |',
        '| --- | --- | --- | --- | --- | --- | --- |',
    ]
    for ur_type, loop_hz, measured in results:
        cells = ['%.0f (%.0f-%.0f)' % (1e6 * benchlib.median(measured[c]), 1e6 * min(measured[c]),
                                       1e6 * max(measured[c])) for c in CASES]
        none = benchlib.median(measured['no client'])
        lines.append('| %s | %g ms | %s | %s | %s | %.2f | %.2f |' % (
            ur_type, 1000.0 / loop_hz, cells[0], cells[1], cells[2], benchlib.median(measured['RTDE']) / none,
            benchlib.median(measured['every stream']) / none))
    return '\n'.join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=2.0, help='simulated seconds per chunk')
    parser.add_argument('--runs', type=int, default=5, help='chunks of each case')
    parser.add_argument('--output', help='RESULTS.md to write the section "network_faces" into')
    args = parser.parse_args(argv)
    load = benchlib.load_average()
    text = section(bench(args.seconds, args.runs), args.seconds, args.runs, load)
    print(text)
    if args.output:
        benchlib.replace_section(args.output, 'network_faces', text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
