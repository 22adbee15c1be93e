"""Bad programs never harm the node: the URScript interpreter and the arm's core under mutated programs.

Every program of test/data/urscript (whatever is there when the test runs) is mutated the way a
user's typo or a bad generator would mutate it: lines deleted, duplicated or swapped; tokens
deleted or inserted; operators, numbers, indexes, function names and argument counts changed;
`end` dropped, brackets unbalanced, expressions and blocks nested deep. A fixed seed makes the same
mutants every run. Each mutant goes to a real ArmCore on script_command and runs for a bounded
number of control cycles, and must end as the robot's programs end:

- refused: it does not compile; one ERROR line names a line of the program; nothing runs;
- runtime error: it stops with the robot's runtime exception, in the robot's log and on one line;
- ran: it finished, or still runs when its cycles are up.

Whatever it does, no Python exception leaves script_command or step, no message spans lines, and
every step returns a snapshot with finite joint positions within the limits: the node publishes
joint_states from each step's snapshot, so they never stop.

A failure names the seed, the mutant's index and text, and the mutant its core was built at (a core
serves MUTANTS_PER_CORE mutants in turn): `mutants(SEED, index + 1, corpus(), function_names(served))`
makes them again from the same corpus.
"""
import os
import re
import traceback

import numpy as np
import pytest

from ur3_ft_gripper_description.devices.ur_arm import core as arm_core
from ur3_ft_gripper_description.model.names import shared_rospack
from ur3_ft_gripper_description.devices.ur_arm import joints as jm
from ur3_ft_gripper_description.devices.ur_arm import robot_state as rs
from ur3_ft_gripper_description.devices.ur_arm.settings import read_settings
from ur3_ft_gripper_testing.urscript_mutants import CORPUS, corpus, function_names, mutants

SEED = 20240611       # any fixed number: a failure names it with the mutant's index
MUTANTS = 3000
CYCLES = 60           # control cycles each mutant runs at most (CB3: 0.48 s, e-Series: 0.12 s)
MUTANTS_PER_CORE = 100
# CB3 and e-Series alternate, a core each: their robots offer different functions and cycles.
MODELS = ('ur3e', 'ur3')
STARTED = 'joint_state_controller scaled_pos_joint_traj_controller speed_scaling_state_controller ' \
          'force_torque_sensor_controller'
LIMIT_SLACK = 1e-9    # rad: the joints stop at their limits, up to rounding

COMPILE_ERROR = re.compile(r'script_command: the robot would not compile this script: line (\d+): \S')
RUNTIME_EXCEPTION = re.compile(r'script_command: (RuntimeException: Runtime error in line (\d+), column \d+ '
                               r'Error: \S.*); program stopped$')
REFUSED, RUNTIME_ERROR, RAN = 'refused', 'runtime error', 'ran'
# Python's own exception texts: the robot's runtime error names URScript's types (int, float, list, pose),
# never a Python class or phrase.
PYTHON_WORDING = re.compile(r"between instances of|unsupported operand|object is not|NoneType|object has no "
                            r"attribute|positional argument|invalid literal|must be real number|'(list|int|float|"
                            r"str|tuple|dict|Pose)'")


# -- the arm's core, as the node builds it --------------------------------------------------------

def make_core(configured_model, ur_type):
    config = os.path.join(shared_rospack().get_path('ur_robot_driver'), 'config', '%s_controllers.yaml' % ur_type)
    values = {'~ur_type': ur_type, '~controller_config_file': config, '~controllers': STARTED,
              'robot_description': configured_model(ur_type, False, False).text}
    settings = read_settings(lambda name, default=None: values.get(name, default))
    return arm_core.ArmCore(settings, jm.KinematicJoints.from_settings(settings)), 1.0 / settings.loop_hz


# -- running a mutant --------------------------------------------------------------------------------

class Misbehaviour(Exception):
    """What a bad program did to the node that it must never do."""


def check_snapshot(core, snapshot):
    if not isinstance(snapshot, arm_core.Snapshot):
        raise Misbehaviour('step returned %r, not a Snapshot: no joint_states this cycle' % (snapshot,))
    position = np.asarray(snapshot.position, dtype=float)
    if position.shape != (6,) or not np.all(np.isfinite(position)) or not np.all(np.isfinite(snapshot.velocity)):
        raise Misbehaviour('joint_states would carry %s, velocity %s' % (position, snapshot.velocity))
    if np.any(position < core.arm.lower - LIMIT_SLACK) or np.any(position > core.arm.upper + LIMIT_SLACK):
        raise Misbehaviour('joint positions %s beyond the limits %s .. %s' % (position, core.arm.lower, core.arm.upper))


def checked_messages(core):
    messages = core.take_messages()
    for level, text in messages:
        if '\n' in text or '\r' in text:
            raise Misbehaviour('a message over several lines: %r' % text)
    return messages


def line_count(text):
    return max(1, len(text.rstrip().splitlines()))


def run_mutant(core, dt, text, cycles):
    """REFUSED, RUNTIME_ERROR or RAN; Misbehaviour for anything else (Python's exceptions go through)."""
    checked_messages(core)
    running_before = core.script_run
    core.script_command(text)
    primary = core.script_run is not running_before  # a secondary program runs beside, replacing nothing
    messages = checked_messages(core)
    if messages and COMPILE_ERROR.match(messages[0][1]):
        line = int(COMPILE_ERROR.match(messages[0][1]).group(1))
        if len(messages) != 1 or messages[0][0] != arm_core.ERROR:
            raise Misbehaviour('a refusal said more than its one ERROR line: %r' % messages)
        if not 1 <= line <= line_count(text):
            raise Misbehaviour('the refusal names line %d of a program of %d' % (line, line_count(text)))
        if core.script_running or core.secondary_runs:
            raise Misbehaviour('a refused program runs')
        check_snapshot(core, core.step(dt))
        if checked_messages(core):
            raise Misbehaviour('a refused program has more to say')
        return REFUSED
    errors = [m for m in messages if m[0] != arm_core.INFO]
    for _ in range(cycles):
        if not core.script_running and not core.secondary_runs:
            break
        check_snapshot(core, core.step(dt))
        errors += [m for m in checked_messages(core) if m[0] != arm_core.INFO]
    if not errors:
        return RAN
    exception = RUNTIME_EXCEPTION.match(errors[0][1])
    if len(errors) != 1 or exception is None:
        raise Misbehaviour('other than one runtime exception: %r' % errors)
    if PYTHON_WORDING.search(exception.group(1)):
        raise Misbehaviour('the runtime exception speaks Python, not URScript: %r' % exception.group(1))
    if exception.group(1) not in core.robot.log:
        raise Misbehaviour('the runtime exception is not in the robot log: %r' % exception.group(1))
    # Line 0: a motion that fails while it runs, between the program's instructions.
    if not 0 <= int(exception.group(2)) <= line_count(text):
        raise Misbehaviour('the runtime exception names line %s of a program of %d' % (exception.group(2),
                                                                                     line_count(text)))
    if core.script_running or core.secondary_runs:
        raise Misbehaviour('the program runs on after its runtime exception')
    if primary and core.robot.program_state != rs.STOPPED:
        raise Misbehaviour('the program state is %s after a runtime exception' % core.robot.program_state)
    return RUNTIME_ERROR


def end_program(core, dt):
    """The next program replaces a running one: a program that halts at once ends it (a secondary ends itself).

    Not the dashboard's stop: it stops the program state, but the core keeps the URScript program, and
    a play after it would run that program on.
    """
    if core.script_running:
        core.script_command('halt')
    for _ in range(3):
        if not core.script_running and not core.secondary_runs:
            break
        check_snapshot(core, core.step(dt))
    checked_messages(core)
    if core.script_running or core.secondary_runs:
        raise Misbehaviour('the program did not end when another replaced it')


def describe(seed, index, first_on_core, ur_type, source, text, reason):
    return ('seed %d, mutant %d (of %s; on a fresh %s core from mutant %d on): %s\n--- mutant %d ---\n%s\n---'
            % (seed, index, source, ur_type, first_on_core, reason, index, text))


# Infinite and NaN numbers are what the mutants feed the pose math: numpy warns of them, the program stops.
@pytest.mark.filterwarnings('ignore::RuntimeWarning')
def test_mutated_programs_are_refused_stop_with_a_runtime_error_or_run(configured_model):
    programs = corpus()
    assert programs, 'no programs in %s' % CORPUS
    probe, _ = make_core(configured_model, MODELS[0])
    functions = function_names(probe.script_robot.served())
    counts = {REFUSED: 0, RUNTIME_ERROR: 0, RAN: 0}
    failures = []
    core, first_on_core = None, 0
    for index, (source, text) in enumerate(mutants(SEED, MUTANTS, programs, functions)):
        if core is None or index - first_on_core >= MUTANTS_PER_CORE:
            ur_type = MODELS[(index // MUTANTS_PER_CORE) % len(MODELS)]
            (core, dt), first_on_core = make_core(configured_model, ur_type), index
        try:
            counts[run_mutant(core, dt, text, CYCLES)] += 1
            end_program(core, dt)
        except Exception as exc:  # any: a Python exception out of the core is what this test looks for
            reason = exc if isinstance(exc, Misbehaviour) else '%s: %s, from\n%s' % (
                type(exc).__name__, exc, ''.join(traceback.format_tb(exc.__traceback__)[-3:]))
            failures.append(describe(SEED, index, first_on_core, ur_type, source, text, reason))
            core = None  # whatever state it is in, the next mutant gets a fresh one
            if len(failures) >= 5:
                break
    summary = '%d mutants of %d programs: %s' % (sum(counts.values()), len(programs),
                                                ', '.join('%s %d' % item for item in counts.items()))
    print(summary)
    assert not failures, summary + '\n\n' + '\n\n'.join(failures)
    assert all(counts.values()), 'the mutants do not reach every outcome: ' + summary


def test_the_same_seed_makes_the_same_mutants(configured_model):
    core, _ = make_core(configured_model, MODELS[0])
    programs, functions = corpus(), function_names(core.script_robot.served())
    assert mutants(SEED, 50, programs, functions) == mutants(SEED, 50, programs, functions)


# -- what the fuzz found, each on its own ------------------------------------------------------------

@pytest.fixture
def arm(configured_model):
    return make_core(configured_model, 'ur3e')


@pytest.mark.parametrize('program, line', [
    ('x = ' + '-' * 3000 + '1', 1),
    ('x = ' + '[' * 1000 + '1' + ']' * 1000, 1),
    ('x = ' + 'norm(' * 1000 + '1' + ')' * 1000, 1),
    ('x = ' + ' + '.join(['1'] * 3000), 1),
    ('textmsg("deep")\n' + 'if True:\n' * 400 + 'x = 1\n' + 'end\n' * 400, 102),
], ids=['minus signs', 'lists', 'calls', 'a sum', 'blocks'])
def test_a_program_nested_too_deeply_is_refused_naming_the_line(arm, program, line):
    # Python's recursion limit used to end script_command with a RecursionError instead.
    core, dt = arm
    core.script_command(program)
    [(level, text)] = core.take_messages()
    assert level == arm_core.ERROR and 'line %d: nested too deeply' % line in text, text
    assert not core.script_running


def test_nesting_as_deep_as_programs_go_compiles_and_runs(arm):
    core, dt = arm
    program = ('def deep():\n' + '  if True:\n' * 30 + '  x = ' + '[' * 30 + ' + '.join(['1'] * 30) + ']' * 30 +
               '\n' + '  end\n' * 30 + '  textmsg("deep")\nend')
    assert run_mutant(core, dt, program, 3) == RAN and core.robot.log[-1] == 'deep'


@pytest.mark.parametrize('program', [
    'set_tool_digital_out(1e309, False)',
    'set_standard_digital_out([1], True)',
    'x = pow(2, 1e308)',
    'x = 1e309 % 2',
    'x = %s / 2' % ('9' * 400),
    'x = pose_trans(p[0, 0, 0, 0, 1e309, 0], p[0, 0, 0, 0, 0, 0])',
    'x = pose_trans(p[0, 0, 0, 0, 0 * 1e309, 0], p[0, 0, 0, 0, 0, 0])',
    'x = interpolate_pose(p[0, 0, 0, 0, 0, 0], p[0, 0, 0, 0, 0, 1], 0 * 1e309)',
], ids=['int of infinity', 'int of a list', 'pow overflow', 'fmod of infinity', 'int too large for a float',
        'infinite rotation', 'NaN rotation', 'NaN alpha'])
@pytest.mark.filterwarnings('ignore::RuntimeWarning')
def test_values_python_cannot_compute_with_stop_the_program_with_a_runtime_error(arm, program):
    # Python's OverflowError, TypeError, ValueError and numpy's LinAlgError used to leave step().
    core, dt = arm
    assert run_mutant(core, dt, program, 3) == RUNTIME_ERROR


def test_a_secondary_programs_runtime_exception_is_said_once(arm):
    # A secondary program that failed on its first step stayed listed, and the next cycle said it again.
    core, dt = arm
    assert run_mutant(core, dt, 'sec s():\n  set_tool_digital_out("", False)\nend', 3) == RUNTIME_ERROR
    assert sum(entry.startswith('RuntimeException') for entry in core.robot.log) == 1
