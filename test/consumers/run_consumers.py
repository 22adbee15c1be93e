"""Run test/consumers (pytest, arguments passed on) under the Python that has the consumer libraries.

That is $UR3_FT_GRIPPER_CONSUMERS_PYTHON (tools/quickstart's consumers venv:
pinocchio, MuJoCo, PyBullet, python-fcl with numpy 2, kept out of the ROS
workspace's Python), else this Python. A library missing there fails the
tests at import: nothing is skipped. $UR3_FT_GRIPPER_CONSUMERS_ABSENT names
the consumers that no registry has for this release (its table in
tools/releases/, key consumers_absent): their test files are not collected,
and one line says so.
"""
import os
import subprocess
import sys

if __name__ == '__main__':
    python = os.environ.get('UR3_FT_GRIPPER_CONSUMERS_PYTHON') or sys.executable
    here = os.path.dirname(os.path.abspath(__file__))
    ignored = []
    for consumer in os.environ.get('UR3_FT_GRIPPER_CONSUMERS_ABSENT', '').split():
        path = os.path.join(here, 'test_%s.py' % consumer)
        if not os.path.isfile(path):
            sys.exit('run_consumers: UR3_FT_GRIPPER_CONSUMERS_ABSENT names %s, but there is no %s' % (consumer, path))
        print('run_consumers: %s not collected: this release has no %s (tools/releases/)' % (path, consumer))
        ignored.append('--ignore=' + path)
    sys.exit(subprocess.call([python, '-m', 'pytest', here, '-p', 'no:cacheprovider'] + ignored + sys.argv[1:]))
