"""Busy processes beside a test, as on a shared CI runner: one CPU-bound loop per core.

`CpuLoad` starts them and stops them (a context manager; `NoLoad` is the
quiet machine's). Each process spins in plain Python arithmetic and ends when
its parent is gone.
"""
import multiprocessing
import os
import signal


def _spin(parent):
    # A fork of a rospy node inherits its handlers, which turn SIGTERM into a rospy shutdown that this
    # loop never looks at: the default ends the process.
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_DFL)
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
            if process.is_alive():
                process.kill()
                process.join(5)
        self.processes = []
        return False


class NoLoad(object):
    """The quiet machine: nothing started."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False
