"""The benchmarks import what exists: every name a bench/ script imports from this package, anywhere in it.

The benchmarks run by hand (doc/benchmarks.md), not in the suite, and most import the package inside
their functions, so a renamed or moved name only shows when someone runs them. This reads each
script's `from ur3_ft_gripper_description... import name` statements, at any depth, and checks that
each module imports and has each name.
"""
import ast
import glob
import importlib
import os

import pytest

from ur3_ft_gripper_testing.model import PACKAGE_DIR

PACKAGE = 'ur3_ft_gripper_description'
SCRIPTS = sorted(glob.glob(os.path.join(PACKAGE_DIR, 'bench', '*.py')))


def imported_names(path):
    """(line, module, name) of each name imported from this package in the file at `path`."""
    tree = ast.parse(open(path).read(), path)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module and (
                node.module == PACKAGE or node.module.startswith(PACKAGE + '.')):
            found.extend((node.lineno, node.module, alias.name) for alias in node.names)
    return sorted(found)


def missing_names(path):
    """'file:line: module has no name' for each import of `path` that would fail."""
    problems = []
    for line, module, name in imported_names(path):
        try:
            imported = importlib.import_module(module)
        except ImportError as exc:
            problems.append('%s:%d: %s does not import (%s)' % (os.path.basename(path), line, module, exc))
            continue
        if not hasattr(imported, name):
            try:  # a submodule, as in `from package import module`
                importlib.import_module('%s.%s' % (module, name))
            except ImportError:
                problems.append('%s:%d: %s has no %s' % (os.path.basename(path), line, module, name))
    return problems


def test_there_are_benchmarks_importing_the_package():
    assert any(imported_names(path) for path in SCRIPTS), SCRIPTS


@pytest.mark.parametrize('path', SCRIPTS, ids=[os.path.basename(p) for p in SCRIPTS])
def test_each_name_a_benchmark_imports_from_the_package_exists(path):
    assert missing_names(path) == []


def test_a_name_that_moved_is_found(tmp_path):
    script = tmp_path / 'moved.py'
    script.write_text('def run():\n    from %s.devices.ur_arm.physics_joints import JointCommand\n' % PACKAGE)
    assert missing_names(str(script)) == ['moved.py:2: %s.devices.ur_arm.physics_joints has no JointCommand'
                                          % PACKAGE]
