"""Run test/consumers (pytest, arguments passed on) under the Python that has the consumer libraries.

That is $UR3_FT_GRIPPER_CONSUMERS_PYTHON (tools/quickstart's consumers venv:
pinocchio, MuJoCo, PyBullet, python-fcl with numpy 2, kept out of the ROS
workspace's Python), else this Python. A library missing there fails the
tests at import: nothing is skipped.
"""
import os
import subprocess
import sys

if __name__ == '__main__':
    python = os.environ.get('UR3_FT_GRIPPER_CONSUMERS_PYTHON') or sys.executable
    here = os.path.dirname(os.path.abspath(__file__))
    sys.exit(subprocess.call([python, '-m', 'pytest', here, '-p', 'no:cacheprovider'] + sys.argv[1:]))
