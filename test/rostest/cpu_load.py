#!/usr/bin/env python3
"""A launch file's busy neighbour: one CPU-bound process per core until roslaunch stops it."""
import sys

from ur3_ft_gripper_testing.cpu_load import main

if __name__ == '__main__':
    sys.exit(main())
