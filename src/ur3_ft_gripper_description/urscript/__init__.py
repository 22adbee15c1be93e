"""URScript, the language of Universal Robots controllers: parser and interpreter, no robot.

    program = compile_script(text, served)   # raises CompileError naming the line
    run = Run(program, robot)
    while not run.finished:
        run.step(0.002)                       # one control cycle
    run.error                                 # None, or a RuntimeFault

`served` is {function name: physical_time} of what the robot side
implements (moves, I/O, state); `robot.call(name, args, kwargs)` runs those
and returns a value or a `Blocking`, and `robot.call_method(handle, name,
args)`, where the robot has it, a method of a handle one of its functions
gave (a remote procedure of rpc_factory's). The language's own functions (math,
pose math, strings, lists, sleep, sync) live here. A function the URScript
manual has (MANUAL_FUNCTIONS, from manual_functions.txt) that nobody
implements refuses the script with "is a URScript function the simulated
robot does not offer"; a name nobody knows with the robot's own wording,
"name 'x' is not defined". A script nested deeper than parser.MAX_NESTING
(100 blocks, brackets, calls or operators inside one another) is refused
naming the line: the manual sets no limit, Python's stack does. What Python
cannot compute with (an int too large for a float, a rotation of infinite
angle) stops the program with a runtime error, as the robot's own errors do.

What a script is: one top-level `def name(): ... end` (a program) or
`sec name(): ... end` (a secondary program, which may use no physical time:
no sleep, sync or call served with physical_time True; refused whole,
naming the line), optionally followed by a call of it, which the robot does
not need and which is dropped. Any other text is a program of bare
statements, as the robot wraps them: its top-level defs and threads are
definitions, the rest runs in order; `name` is None then.

The grammar is grammar.lark (LALR, lark-parser 0.8.1 to lark 1.x). How the
interpreter schedules threads is in machine.py, the operators' semantics in
values.py, the pose math in functions.py.
"""

import os

from .compiler import Program, compile_tree
from .machine import Blocking, Run, ThreadHandle
from .parser import CompileError, parse
from .values import Pose, RuntimeFault, to_str

MANUAL_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'manual_functions.txt')


def _manual_functions():
    with open(MANUAL_FILE) as f:
        return frozenset(line.strip() for line in f if line.strip() and not line.startswith('#'))


MANUAL_FUNCTIONS = _manual_functions()


def compile_script(text, served):
    """The Program of a URScript text; CompileError (line, column) if the robot would refuse it."""
    return compile_tree(parse(text), served, MANUAL_FUNCTIONS, text)


__all__ = ['compile_script', 'CompileError', 'Run', 'Blocking', 'RuntimeFault', 'Pose', 'MANUAL_FUNCTIONS',
           'Program', 'ThreadHandle', 'to_str']
