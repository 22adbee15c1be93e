"""The `cell` mark on the test files test/variant_scope.yaml names as the cell's behaviour.

test/unit and test/bringup hold both kinds: tests of the model and what reads it, which run in every
robotiq variant's pass, and tests of the cell's behaviour, which run in one pass per machine. CMake's
targets pick them with `-m cell` and `-m "not cell"`; every test is in exactly one of the two.
A folder's conftest.py takes the two hooks below by importing them.
"""
import os

import pytest
import yaml

TEST_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCOPE_FILE = os.path.join(TEST_DIR, 'variant_scope.yaml')
MARK = 'cell'


def cell_files(scope_file=SCOPE_FILE):
    """The real paths of the files the scope file names under `cell_files` (relative to test/): a workspace
    may reach the package through a link."""
    with open(scope_file) as stream:
        listed = (yaml.safe_load(stream) or {}).get('cell_files') or []
    return {os.path.realpath(os.path.join(os.path.dirname(scope_file), name)) for name in listed}


def pytest_configure(config):
    config.addinivalue_line('markers', '%s: a test of the cell\'s behaviour (test/variant_scope.yaml), run in '
                                       'one robotiq variant\'s pass per machine' % MARK)


@pytest.hookimpl(tryfirst=True)  # before -m selects by the marks
def pytest_collection_modifyitems(items):
    """Puts the `cell` mark on the items whose file the scope file names."""
    files = cell_files()
    for item in items:
        if os.path.realpath(str(getattr(item, 'path', None) or item.fspath)) in files:
            item.add_marker(getattr(pytest.mark, MARK))
