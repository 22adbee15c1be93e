"""Every fault tools/motion_mutants.py plants in a motion primitive of tool_motion.py is caught by a test.

The full run copies src/ once per fault and runs test_tool_motion.py (and the
motion tests of test_ur_arm_core.py) against the copy; the fast tests check
that the list still applies to today's tool_motion.py and covers every
primitive.

A test of the tests, run once by tools/quickstart test in the sourced workspace
(the faults are in the package's own code, the same under every Python), not in each Python leg.
"""
import importlib.util
import os
import subprocess
import sys

from ur3_ft_gripper_testing.model import PACKAGE_DIR

TOOL = os.path.join(PACKAGE_DIR, 'tools', 'motion_mutants.py')
# URScript's motion primitives (and the blend between two moves): each gets at least one fault.
PRIMITIVES = {'movej', 'movel', 'movep', 'servoj', 'speedj', 'stopj', 'speedl', 'stopl', 'blend'}


def load_tool():
    spec = importlib.util.spec_from_file_location('motion_mutants', TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_fault_still_applies_exactly_once_and_compiles():
    mm = load_tool()
    text = mm.module_text()
    assert mm.stale(text) == []
    for mutant in mm.MUTANTS:
        assert mm.mutate(text, mutant) != text, mutant.name
    # A fault whose text has gone from the module (or occurs twice) is named, not silently skipped.
    first = mm.MUTANTS[0]
    assert mm.stale(text.replace(first.source, ''))[0] == (first.name, 0)
    assert mm.stale(text + first.source)[0] == (first.name, 2)


def test_every_primitive_has_a_fault_and_every_fault_a_name_of_its_own():
    mm = load_tool()
    assert PRIMITIVES <= set(m.primitive for m in mm.MUTANTS)
    assert set(m.primitive for m in mm.MUTANTS) <= PRIMITIVES
    names = [m.name for m in mm.MUTANTS]
    assert len(names) == len(set(names))


def test_an_unknown_fault_name_is_one_line():
    run = subprocess.run([sys.executable, TOOL, '--only', 'no-such-fault'], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True)
    assert run.returncode != 0 and run.stdout == ''
    assert run.stderr.count('\n') == 1 and 'no-such-fault' in run.stderr


def test_every_planted_fault_is_caught():
    mm = load_tool()
    baseline, results = mm.run_all(mm.MUTANTS)
    assert baseline.caught is False, 'the motion tests fail unmutated: %s' % baseline.caught_by
    assert [r.mutant.name for r in results] == [m.name for m in mm.MUTANTS]
    survivors = ['%s (%s: %s)%s' % (r.mutant.name, r.mutant.primitive, r.mutant.fault,
                                    '' if r.caught is False else ': ' + r.caught_by)
                 for r in results if not r.caught]
    assert not survivors, 'faults no test catches: ' + '; '.join(survivors)
