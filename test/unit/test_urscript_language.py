"""The URScript language package: the scripts users send, compiled and run on simulated time.

The scripts are test/data/urscript/*.script (those in arm/ run on the arm's
core, in test_urscript_corpus.py). `CellRobot` below stands for the robot
side: its `call` records each served call and answers as the arm's core does
(a value, or a `Blocking` for a move that takes a few cycles).
Each test works out what the script must do on its own (the log lines, the
calls, the cycle a thread ends in) and compares.
"""
import math
import os
import time

import numpy as np
import pytest

from ur3_ft_gripper_testing.model import PACKAGE_DIR

from ur3_ft_gripper_description.urscript import (MANUAL_FUNCTIONS, Blocking, CompileError, Pose, Run,
                                                  RuntimeFault, compile_script, to_str)

CORPUS = os.path.join(PACKAGE_DIR, 'test', 'data', 'urscript')
DT = 0.002  # an e-Series control cycle

# name: physical_time, as a robot side would serve them.
SERVED = {'textmsg': False, 'movej': True, 'movel': True, 'force_mode': True, 'tool_pose': False,
          'set_standard_digital_out': False, 'set_tool_digital_out': False, 'get_actual_tcp_pose': False,
          'get_standard_digital_in': False}


class CellRobot(object):
    """The robot side of a run: records calls; a move takes `move_cycles` control cycles."""

    def __init__(self, move_cycles=3):
        self.calls = []
        self.log = []
        self.move_cycles = move_cycles

    def call(self, name, args, kwargs):
        self.calls.append((name, args, kwargs))
        if name == 'textmsg':
            self.log.append(''.join(to_str(a) for a in args))
            return None
        if name in ('movej', 'movel'):
            polls = []

            def done():
                polls.append(1)
                return len(polls) >= self.move_cycles
            return Blocking(done)
        if name in ('tool_pose', 'get_actual_tcp_pose'):
            return Pose([0.1, 0.2, 0.3, 0.0, 0.0, 0.0])
        return None


def script(name):
    with open(os.path.join(CORPUS, name)) as f:
        return f.read()


def run_to_end(text, robot=None, served=SERVED, max_cycles=10000):
    robot = robot or CellRobot()
    run = Run(compile_script(text, served), robot)
    cycles = 0
    while not run.finished and cycles < max_cycles:
        run.step(DT)
        cycles += 1
    return run, robot, cycles


def compile_error(text, served=SERVED):
    with pytest.raises(CompileError) as caught:
        compile_script(text, served)
    return caught.value


# --- the corpus compiles ---------------------------------------------------------------

COMPILING = sorted(n for n in os.listdir(CORPUS) if n.endswith('.script')
                   and n not in ('missing_end.script', 'secondary_sleep.script'))


@pytest.mark.parametrize('name', COMPILING)
def test_each_corpus_script_compiles(name):
    compile_script(script(name), SERVED)


def test_the_force_mode_watchdog_compiles_and_holds_force_mode_until_replaced():
    program = compile_script(script('force_mode_watchdog.script'), {'force_mode': True, 'tool_pose': False})
    assert (program.name, program.secondary) == ('force_watchdog', False)
    robot = CellRobot()
    run = Run(program, robot)
    for _ in range(500):
        run.step(DT)
    assert not run.finished and run.error is None
    assert [c[0] for c in robot.calls] == ['tool_pose', 'force_mode']
    _, args, kwargs = robot.calls[1]
    assert args == [[0.1, 0.2, 0.3, 0, 0, 0], [1, 0, 1, 0, 0, 0], [5, 0, 5, 0, 0, 0], 2,
                    [0.1, 0.1, 0.1, 0.17, 0.17, 0.17]] and kwargs == {}
    assert isinstance(args[0], Pose)
    assert run.running_line == 5  # the sync() loop
    run.stop()
    assert run.finished and run.error is None


# --- control flow, functions, values ---------------------------------------------------

def test_while_if_elif_else_break_continue_and_the_boolean_operators():
    run, robot, _ = run_to_end(script('control_flow.script'))
    odd_below_ten = sum(i for i in range(1, 10) if i % 2)
    assert run.error is None
    assert robot.log == ['total %d' % odd_below_ten, 'branch taken']


def fib(n):
    a, b = 0, 1
    for _ in range(n):
        a, b = b, a + b
    return a


def test_functions_recursion_defaults_named_arguments_and_division():
    run, robot, _ = run_to_end(script('functions.script'))
    assert run.error is None
    # `/` of two ints is a float; `%` keeps the dividend's sign (C's remainder).
    assert robot.log == ['fib %d' % fib(12), 'scaled 10', 'scaled %d' % (5 * 3 + 1), 'ratio 3.5',
                         'remainder %d' % -(7 % 3)]


def test_the_manuals_scoping_rules():
    run, robot, _ = run_to_end(script('scope.script'))
    assert run.error is None
    # set_a writes the global a; masked's `local b` hides the global b, which
    # nested() (a function inside masked) writes; c is counter's own.
    assert robot.log == ['masked 20', 'a 1', 'b 30', 'counter 5']
    assert run.globals['a'] == 1 and run.globals['b'] == 30 and 'c' not in run.globals


def test_halt_ends_the_program_where_it_stands():
    run, robot, cycles = run_to_end(script('halt.script'))
    assert run.finished and run.error is None and cycles == 1
    assert robot.log == ['before']


def test_bare_statements_are_a_program_with_its_definitions():
    program = compile_script(script('bare_statements.script'), SERVED)
    assert program.name is None and not program.secondary
    run, robot, _ = run_to_end(script('bare_statements.script'))
    assert robot.log == ['twice 42']
    assert robot.calls[-1] == ('movej', [[0, -1.57, 0, -1.57, 0, 0]], {'a': 1.4, 'v': 1.05})


def test_a_call_after_the_program_def_runs_it_once():
    text = 'def prog():\n  textmsg("once")\nend\nprog()\n'
    program = compile_script(text, SERVED)
    assert program.name == 'prog'
    _, robot, _ = run_to_end(text)
    assert robot.log == ['once']


def test_poses_literals_indexing_element_assignment_and_pose_trans():
    run, robot, _ = run_to_end(script('poses.script'))
    assert run.error is None

    def matrix(p):
        axis = np.array(p[3:])
        angle = np.linalg.norm(axis)
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]]) / angle
        t = np.eye(4)
        t[:3, :3] = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k.dot(k)
        t[:3, 3] = p[:3]
        return t
    grasp = matrix([0.4, -0.1, 0.2, 0, 0, 1.5707963]).dot(matrix([0.05, 0, 0.1, 3.1415926, 0, 0]))
    (name, (above,), kwargs) = robot.calls[-2][0], robot.calls[-2][1], robot.calls[-2][2]
    assert name == 'movel' and kwargs == {'a': 1.2, 'v': 0.25} and isinstance(above, Pose)
    assert np.allclose(above[:3], grasp[:3, 3] + [0, 0, 0.1], atol=1e-9)
    assert np.allclose(matrix(above)[:3, :3], grasp[:3, :3], atol=1e-6)
    # `above = grasp` copied the pose: raising above left grasp where it was.
    assert robot.log[0].startswith('grasp p[') and robot.log[0] != robot.log[1]
    assert robot.calls[-1] == ('movej', [[0.2, -1.5, 1.2, 0, 0, 0]], {})


# --- threads and physical time ------------------------------------------------------------

def test_threads_run_join_kill_on_simulated_time():
    run, robot, cycles = run_to_end(script('threads.script'))
    assert run.error is None
    # worker sleeps 0.01 s from the first cycle; ticker counts one per cycle
    # until join returns in the cycle worker ends.
    worker_ends = int(round(0.01 / DT)) + 1
    assert robot.log == ['worker done True', 'ticks %d' % worker_ends]
    assert cycles == worker_ends


def test_a_move_blocks_its_thread_for_the_cycles_the_robot_takes():
    text = 'textmsg("start")\nmovej([0, 0, 0, 0, 0, 0])\ntextmsg("moved")\n'
    robot = CellRobot(move_cycles=4)
    run = Run(compile_script(text, SERVED), robot)
    run.step(DT)
    assert robot.log == ['start'] and run.running_line == 2
    for _ in range(3):
        run.step(DT)
        assert robot.log == ['start']
    run.step(DT)  # the fourth poll says done
    assert robot.log == ['start', 'moved'] and run.finished


def test_a_blocking_call_evaluates_to_the_result_the_robot_set():
    class Robot(CellRobot):
        def call(self, name, args, kwargs):
            if name == 'get_standard_digital_in':
                answer = Blocking(lambda: True)
                answer.result = True
                return answer
            return CellRobot.call(self, name, args, kwargs)
    run, robot, cycles = run_to_end('x = get_standard_digital_in(0)\ntextmsg(x)\n', Robot())
    assert robot.log == ['True'] and cycles == 2


def test_sleep_lasts_its_time_and_at_least_one_cycle():
    run, robot, cycles = run_to_end('sleep(0.0101)\ntextmsg("awake")\n')
    assert cycles == int(math.ceil(0.0101 / DT)) + 1
    run, robot, cycles = run_to_end('sleep(0)\nsync()\ntextmsg("awake")\n')
    assert cycles == 3


def test_a_thread_without_physical_time_is_put_aside_each_frame_and_main_goes_on():
    robot = CellRobot()
    run = Run(compile_script(script('busy_thread.script'), SERVED), robot, budget=5000)
    started = time.time()
    cycles = 0
    while not run.finished:
        run.step(DT)
        cycles += 1
    assert time.time() - started < 10
    assert robot.log == ['main awake'] and cycles == 4
    assert run.globals['spins'] > 3 * 100  # it did run, frame after frame


def test_a_main_loop_without_physical_time_never_hangs_step():
    run = Run(compile_script('n = 0\nwhile True:\n  n = n + 1\nend\n', SERVED), CellRobot(), budget=2000)
    for _ in range(5):
        run.step(DT)
    assert not run.finished and run.globals['n'] > 0


def test_stop_ends_main_and_its_threads():
    text = 'thread t():\n  while True:\n    sync()\n  end\nend\nh = run t()\nwhile True:\n  sync()\nend\n'
    run = Run(compile_script(text, SERVED), CellRobot())
    run.step(DT)
    run.stop()
    run.step(DT)
    assert run.finished and run.error is None and run.running_line is None


# --- secondary programs ------------------------------------------------------------------

def test_a_secondary_program_sets_outputs_in_one_cycle():
    program = compile_script(script('secondary_io.script'), SERVED)
    assert (program.name, program.secondary) == ('set_outputs', True)
    run, robot, cycles = run_to_end(script('secondary_io.script'))
    assert cycles == 1 and run.error is None
    assert robot.calls == [('set_standard_digital_out', [1, True], {}), ('set_tool_digital_out', [0, False], {})]


def test_a_secondary_program_that_uses_physical_time_is_refused_naming_the_line():
    error = compile_error(script('secondary_sleep.script'))
    assert (error.line, str(error)) == (3, 'line 3: a secondary program may not use physical time: sleep')
    error = compile_error('sec s():\n  x = 1\n  movej([0, 0, 0, 0, 0, 0])\nend\n')
    assert str(error) == 'line 3: a secondary program may not use physical time: movej'


# --- compile errors ----------------------------------------------------------------------

def test_a_block_without_end_is_a_syntax_error():
    error = compile_error(script('missing_end.script'))
    assert error.line == 6 and 'unexpected end of script' in str(error)


@pytest.mark.parametrize('text, message', [
    ('def f():\n  x = 1\nend\nend\n', 'line 4: unexpected "end"'),
    ('x = 1\nif x > 0\n  x = 2\nend\n', 'line 2: unexpected end of line'),  # no ':'
    ('x = [1, 2\ny = 3\n', 'line 2: unexpected "y"'),
    ('x = 3 $ 4\n', 'line 1: a program label ($ 3 "MoveJ") must stand on a line of its own'),
    ('def f():\n  frobnicate(1)\nend\n', "line 2: name 'frobnicate' is not defined"),
    ('textmsg(y)\n', "line 1: name 'y' is not defined"),
    ('def f():\n  movep(p[0, 0, 0, 0, 0, 0])\nend\n', 'line 2: movep is a URScript function the simulated robot '
                                                     'does not offer'),
    ('x = sqrt(4, 2)\n', 'line 1: sqrt takes at most 1 arguments, not 2'),
    ('def f(a, b=1):\n  return a\nend\nf(b=2)\n', 'line 4: f needs a'),
    ('x = 1\nbreak\n', 'line 2: "break" outside a loop'),
    ('x = p[1, 2, 3]\n', 'line 1: a pose has 6 elements, not 3'),
])
def test_compile_errors_name_the_line(text, message):
    error = compile_error(text)
    assert str(error) == message and isinstance(error, ValueError)
    assert error.line == int(message.split(':')[0].split()[1]) and error.column >= 1


def test_the_manual_function_list_is_the_5x_manual():
    assert {'movej', 'movel', 'force_mode', 'textmsg', 'pose_trans', 'sleep', 'sync', 'socket_open',
            'get_actual_tcp_pose', 'set_standard_digital_out', 'floor', 'get_flag'} <= MANUAL_FUNCTIONS
    assert 'frobnicate' not in MANUAL_FUNCTIONS and len(MANUAL_FUNCTIONS) > 200


# --- runtime errors ----------------------------------------------------------------------

def test_an_index_past_the_end_stops_the_program_with_the_robots_report():
    run, robot, _ = run_to_end(script('index_error.script'))
    assert run.finished and isinstance(run.error, RuntimeFault)
    assert (run.error.line, run.error.column) == (5, 5)
    assert run.error.text == 'Index out of bounds: index 6, length 6'
    assert str(run.error) == ('RuntimeException:\nRuntime error in line 5, column 5\n'
                              'Error: Index out of bounds: index 6, length 6')


def test_division_by_zero_is_a_runtime_error_after_what_ran():
    run, robot, _ = run_to_end(script('division_by_zero.script'))
    assert robot.log == ['half 1.5']
    assert (run.error.line, run.error.text) == (4, 'Division by zero')


def test_an_error_in_a_thread_ends_the_whole_program():
    text = 'thread t():\n  sync()\n  x = [1][2]\nend\nrun t()\nwhile True:\n  sync()\nend\n'
    run, _, cycles = run_to_end(text)
    assert run.finished and run.error.line == 3 and cycles == 2


def test_endless_recursion_is_a_runtime_error():
    run, _, _ = run_to_end('def f(n):\n  return f(n + 1)\nend\nf(0)\n')
    assert run.error.line == 2 and 'Stack overflow' in run.error.text


def test_a_robot_refusal_is_a_runtime_error_on_the_calls_line():
    class Robot(CellRobot):
        def call(self, name, args, kwargs):
            raise ValueError('movej: joint 2 out of range')
    run, _, _ = run_to_end('x = 1\nmovej([0, 0, 9, 0, 0, 0])\n', Robot())
    assert (run.error.line, run.error.text) == (2, 'movej: joint 2 out of range')


def test_a_call_python_cannot_compute_is_a_type_error_in_urscripts_words_naming_the_types_given():
    class Robot(CellRobot):
        def call(self, name, args, kwargs):
            return args[0] > 0  # a robot function comparing what it was given, as Python would
    run, _, _ = run_to_end('x = 1\nmovej("fast")\n', Robot())
    assert (run.error.line, run.error.text) == (2, 'Type error: movej cannot take (string)')


# --- what PolyScope and the drivers write ---------------------------------------------------

POLYSCOPE = '''$ 1 "Robot Program"
def Program():
  global n = 0
  $ 2 "Thread_1"
  thread Thread_1():
    $ 3 "Thread_1" "noBreak"
    n = n + 1
  end
  $ 4 "BeforeStart"
  h = run Thread_1()
  join h
  while n < 3:
    $ 5 "Loop n<3"
    $ 6 "n≔n+1" "breakAfter"
    n = n + 1
  end
  if n == 3:
    $ 7 "If n≟3"
    textmsg("n ", n)
  end
end
'''


def test_program_labels_mark_lines_and_change_nothing():
    program = compile_script(POLYSCOPE, SERVED)
    assert program.name == 'Program'  # a label before the def keeps it the program
    run, robot, _ = run_to_end(POLYSCOPE)
    assert run.error is None and robot.log == ['n 3']
    stripped = '\n'.join('' if line.strip().startswith('$') else line for line in POLYSCOPE.splitlines())
    assert robot.calls == run_to_end(stripped)[1].calls


@pytest.mark.parametrize('text, message', [
    ('x = 1\ntextmsg(x) $ 2 "textmsg"\n', 'line 2: a program label ($ 3 "MoveJ") must stand on a line of its own'),
    ('x = [1,\n  $ 2 "Assignment"\n  2]\n', 'line 2: a program label ($ 3 "MoveJ") cannot stand inside brackets'),
    ('x = 1\n$ "MoveJ"\n', 'line 2: a program label is "$", its number, then its text: $ 3 "MoveJ"'),
    ('x = 1\nenter_critical\nx = 2\n', 'line 2: enter_critical without an exit_critical after it in its block'),
    ('x = 1\nexit_critical\n', 'line 2: exit_critical without an enter_critical before it in its block'),
    ('x = 1\nif x > 0:\n  enter_critical\n  x = 2\nend\nexit_critical\n',
     'line 3: enter_critical without an exit_critical after it in its block'),
    ('enter_critical\nwhile True:\n  exit_critical\n  enter_critical\nend\nexit_critical\n',
     'line 3: exit_critical without an enter_critical before it in its block'),
    ('enter_critical = 1\n', 'line 1: unexpected "="'),
])
def test_misplaced_labels_and_unbalanced_critical_sections_are_refused_in_one_line(text, message):
    error = compile_error(text)
    assert str(error) == message and '\n' not in str(error)


# A thread that counts the frames it runs in.
TICKER = '''global ticks = 0
thread ticker():
  while True:
    ticks = ticks + 1
    sync()
  end
end
'''
CRITICAL = TICKER + '''t = run ticker()
sync()
%s
seen_before = ticks
i = 0
while i < 3000:
  i = i + 1
end
seen_after = ticks
%s
sync()
kill t
'''


@pytest.mark.parametrize('critical', [True, False])
def test_a_critical_section_keeps_other_threads_from_running_between_its_statements(critical):
    enter, leave = ('enter_critical', 'exit_critical') if critical else ('', '')
    run = Run(compile_script(CRITICAL % (enter, leave), SERVED), CellRobot(), budget=2000)
    cycles = 0
    while not run.finished:
        run.step(DT)
        cycles += 1
    assert run.error is None
    # Frames: main reaches its sync(), counts over several (2000 instructions a frame), then syncs and
    # kills the ticker. Between its two reads the ticker would tick once a frame but the last.
    computing_frames = cycles - 2
    assert computing_frames >= 3
    ticked = run.globals['seen_after'] - run.globals['seen_before']
    assert ticked == (0 if critical else computing_frames - 1)


def test_physical_time_inside_a_critical_section_lets_the_others_run():
    text = TICKER + ('t = run ticker()\nenter_critical\nbefore = ticks\nsleep(10 * %r)\nafter = ticks\nexit_critical\n'
                     'kill t\n' % DT)
    run, _, _ = run_to_end(text)
    assert run.error is None and run.globals['after'] - run.globals['before'] == 10


def test_return_and_break_leave_the_critical_sections_they_are_in():
    text = TICKER + '''def first_of(values):
  enter_critical
  while True:
    enter_critical
    if True:
      break
    end
    exit_critical
  end
  if get_list_length(values) > 0:
    return values[0]
  end
  exit_critical
  return -1
end
t = run ticker()
sync()
x = first_of([7, 8])
seen_before = ticks
i = 0
while i < 3000:
  i = i + 1
end
seen_after = ticks
kill t
'''
    run = Run(compile_script(text, SERVED), CellRobot(), budget=2000)
    while not run.finished:
        run.step(DT)
    assert run.error is None and run.globals['x'] == 7
    # Nothing holds the ticker off any more: it ticks in the frames the count spans.
    assert run.globals['seen_after'] - run.globals['seen_before'] >= 3
    assert run.main.critical == 0


def test_a_statement_continues_inside_brackets_and_a_block_can_share_its_line():
    text = ('movej([0, -1.57,  # base, shoulder\n'
            '       0, 0, 0, 0], a=1.2,\n'
            '      v=0.5)\n'
            'n = 0 + (1 +\n'
            '   2)\n'
            'if n == 3: textmsg("three") elif n == 4: textmsg("four") else: textmsg("other") end\n'
            'while n > 0: n = n - 1 end\n'
            'x = [1, 2][n + 2]\n')
    run, robot, _ = run_to_end(text)
    assert robot.calls[0] == ('movej', [[0, -1.57, 0, 0, 0, 0]], {'a': 1.2, 'v': 0.5})
    assert robot.log == ['three'] and run.globals['n'] == 0
    # Lines keep their numbers past the continued ones: the index error is on line 8.
    assert (run.error.line, run.error.text) == (8, 'Index out of bounds: index 2, length 2')


def test_a_statement_goes_on_after_an_operator_and_the_next_can_share_its_line():
    # ur_rtde's control script, as every controller it runs on reads it: its register-offset injection leaves
    # `global offset = # comment` with the value on the next line, and the next statement after that value.
    text = ('global offset = # the register offset\n'
            '1    global count = # the count\n'
            '2    total = offset +\n'
            '  count * 3 textmsg(total) textmsg("done")\n'
            'x = total\n'
            '(x)\n')
    run, robot, _ = run_to_end(text)
    assert run.error is None and robot.log == ['7', 'done'] and run.globals['x'] == 7


def test_p_indexes_a_variable_named_p_where_its_brackets_hold_one_expression():
    # ur_rtde's control script scales a pose argument named p element by element.
    text = ('def scale(p, factor):\n  p[0] = p[0] * factor\n  return p\nend\n'
            'q = scale(p[1, 2, 3, 0, 0, 0], 2)\ntextmsg(q[0])\ntextmsg(q[1])\n')
    run, robot, _ = run_to_end(text)
    assert run.error is None and [float(v) for v in robot.log] == [2.0, 2.0]


def test_join_and_kill_of_a_handle_still_at_zero_do_nothing_and_of_another_number_are_type_errors():
    # The drivers' programs set a thread handle to 0 before any run and kill it unconditionally.
    run, robot, _ = run_to_end('global thrd = 0\nkill thrd\njoin thrd\ntextmsg("after")\n')
    assert run.error is None and robot.log == ['after']
    run, _, _ = run_to_end('kill 1\n')
    assert run.error.text == 'Type error: kill takes a thread, not int'
