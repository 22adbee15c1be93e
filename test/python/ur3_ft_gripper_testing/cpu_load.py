"""Busy processes beside a test, as on a shared CI runner: one CPU-bound loop per core.

`CpuLoad` starts them and stops them (a context manager); `main()` runs them
until killed, for a launch file's node (test/rostest/cpu_load.py). Each
process spins in plain Python arithmetic and ends when its parent is gone.
"""
import multiprocessing
import os
import signal
import sys
import time


def _spin(parent):
    x = 0
    while True:
        for _ in range(100000):
            x = (x * 1103515245 + 12345) & 0x7fffffff
        if os.getppid() != parent:
            return


class CpuLoad(object):
    """`processes` busy processes (default: one per core) while in the `with` block."""

    def __init__(self, processes=None):
        self.count = processes or os.cpu_count() or 2
        self.processes = []

    def __enter__(self):
        context = multiprocessing.get_context('fork')
        for _ in range(self.count):
            process = context.Process(target=_spin, args=(os.getpid(),), daemon=True)
            process.start()
            self.processes.append(process)
        return self

    def __exit__(self, *exc):
        for process in self.processes:
            process.terminate()
        for process in self.processes:
            process.join(5)
        self.processes = []
        return False


def main():
    """Spin one process per core until SIGTERM or SIGINT (roslaunch stops its nodes with them)."""
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    with CpuLoad() as load:
        print('cpu_load: %d busy processes' % load.count)
        sys.stdout.flush()
        while not stop:
            time.sleep(0.2)
    return 0
