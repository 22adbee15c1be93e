"""Every Python file of the package runs on Python 3.8, Noetic's Python on Ubuntu 20.04.

vermin (PyPI, pinned in tools/quickstart) reads each file's syntax and the
standard-library names it uses and reports anything newer than 3.8. The files
are the package's *.py files and its executables without the extension
(scripts/), found by their Python shebang.
"""
import os
import subprocess
import sys

from ur3_ft_gripper_testing.model import PACKAGE_DIR

SKIP_DIRS = {'.git', '__pycache__', 'build', 'devel'}


def python_files(root):
    found = []
    for folder, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS)
        for name in sorted(files):
            path = os.path.join(folder, name)
            if name.endswith('.py'):
                found.append(path)
            elif '.' not in name and os.path.isfile(path):
                with open(path, 'rb') as f:
                    first = f.readline()
                if first.startswith(b'#!') and b'python' in first:
                    found.append(path)
    return found


def vermin(*args):
    """vermin's verdict for Python 3.8 on the files in args (its command-line entry point, in this Python)."""
    command = 'import sys, vermin; sys.argv[0] = "vermin"; sys.exit(vermin.main())'
    run = subprocess.run([sys.executable, '-c', command, '--target=3.8-', '--violations', '--no-tips'] +
                         list(args), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         universal_newlines=True, timeout=300)
    assert 'No module named' not in run.stdout, 'vermin is not installed: bash tools/quickstart installs it'
    return run


def test_the_files_include_the_scripts_without_py():
    names = {os.path.relpath(p, PACKAGE_DIR) for p in python_files(PACKAGE_DIR)}
    assert {'scripts/expand_description', 'scripts/export_urdf'} <= names
    assert 'src/ur3_ft_gripper_description/model/description.py' in names
    assert 'tools/quickstart' not in names  # bash


def test_vermin_finds_nothing_newer_than_python_3_8():
    files = python_files(PACKAGE_DIR)
    run = vermin('--eval-annotations', '--no-parse-comments', *files)
    assert run.returncode == 0, run.stdout
    assert 'Analyzing %d files' % len(files) in run.stdout, run.stdout


def test_vermin_would_report_a_python_3_9_feature(tmp_path):
    newer = tmp_path / 'newer.py'
    newer.write_text("print('ur3_'.removeprefix('ur'))\n")
    run = vermin(str(newer))
    assert run.returncode != 0 and 'removeprefix' in run.stdout, run.stdout
