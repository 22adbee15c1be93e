"""Running a compiled program, one control cycle at a time, on simulated time.

`Run.step(dt)` is one control cycle: time advances by dt; threads whose
sleep ended, whose `Blocking` call is done or who called sync() in the last
cycle become runnable; then each runnable thread runs, main first and the
others in the order they were started, until it uses physical time (sleep,
sync, a call the robot answers with `Blocking`), ends, or spends its
instruction budget.

The budget is the manual's thread scheduling: a thread that computes for a
whole frame without using physical time (a loop without sync or sleep) is
put aside until the next frame, so it goes on there and others get their
turn; `step` always returns after at most `budget` instructions per thread,
a call to the robot counting for ROBOT_CALL_COST of them.
A critical section (`enter_critical` ... `exit_critical`) keeps the others
from running while its thread computes: a thread that spends its budget
inside one holds the scheduler, and only it runs, in the next frames too,
until it leaves the section. Physical time inside the section (sleep, sync,
a blocking call) lets the others run while it waits, as the drivers' servo
threads, which call servoj inside one, need.
A secondary program must finish within one step: past its budget it stops
with the error the robot gives ("Runtime is too much behind").

A runtime error, in main or any thread, ends the program: `error` holds a
RuntimeFault with the line and column, and `step` returns normally. When
main ends (its last line, `halt`, an error or `stop()`) every thread is
killed and `finished` is True.
"""

from . import compiler as C
from . import values
from .values import Pose, RuntimeFault

UNSET = object()
MAX_DEPTH = 256  # nested calls before the program stops with a stack overflow
ROBOT_CALL_COST = 100  # instructions of the budget a robot call uses beside its own
PYTHON_VALUE_ERRORS = (ArithmeticError, TypeError, ValueError)


class Blocking(object):
    """A robot call that takes time: the calling thread waits until `done()` is True.

    `done` is polled once per control cycle, from the cycle after the call;
    the call then evaluates to `result`, which the robot may set at any time
    before `done` returns True.
    """

    def __init__(self, done, result=None):
        self.done = done
        self.result = result


class ThreadHandle(object):
    """What `run` gives: the running thread, for join and kill."""

    def __init__(self, thread):
        self.thread = thread

    def __repr__(self):
        return '<thread %s>' % self.thread.name


class _Frame(object):
    __slots__ = ('code', 'pc', 'locals', 'stack')

    def __init__(self, code):
        self.code = code
        self.pc = 0
        self.locals = [UNSET] * len(code.local_names)
        self.stack = []


class _Thread(object):
    def __init__(self, name, code):
        self.name = name
        self.frames = [_Frame(code)]
        self.finished = False
        self.wait = None  # None, ('until', time), ('blocking', Blocking), ('sync',), ('join', _Thread)
        self.spent = False  # has used its slice in this step
        self.critical = 0  # the critical sections it is inside


class Run(object):
    """One run of a compiled Program against a robot (`robot.call(name, args, kwargs)`, and
    `robot.call_method(handle, name, args)` for programs that call a handle's methods)."""

    def __init__(self, program, robot, budget=20000):
        self.program = program
        self.robot = robot
        self.budget = budget
        self.time = 0.0
        self.cycles = 0
        self.globals = {}
        self.finished = False
        self.error = None
        self.main = _Thread(program.name or 'main', program.main)
        self.threads = [self.main]
        self.holder = None  # the thread put aside inside a critical section: only it may run
        self.instructions = 0  # executed so far, for benchmarks

    @property
    def running_position(self):
        """(line, column) main is on (the call it waits in: a motion's runtime error names it), or None
        when finished."""
        if self.finished or not self.main.frames:
            return None
        frame = self.main.frames[-1]
        at = min(frame.pc, len(frame.code.lines) - 1)
        return frame.code.lines[at], frame.code.columns[at]

    @property
    def running_line(self):
        """The line main is on, or None when finished."""
        position = self.running_position
        return None if position is None else position[0]

    def stop(self):
        """End the program at once, as a stop or a replacing program does."""
        self._end()

    def _end(self):
        self.finished = True
        for thread in self.threads:
            thread.finished = True
            thread.frames = []
        self.threads = [self.main]
        self.holder = None

    def _fail(self, fault, thread):
        frame = thread.frames[-1] if thread.frames else None
        if frame is not None and not fault.line:
            at = min(max(frame.pc - 1, 0), len(frame.code.lines) - 1)
            fault.line = frame.code.lines[at]
            fault.column = frame.code.columns[at]
        self.error = fault
        self._end()

    def step(self, dt):
        """One control cycle of dt seconds."""
        if self.finished:
            return
        self.time += dt
        self.cycles += 1
        for thread in self.threads:
            thread.spent = False
        progress = True
        while progress and not self.finished:
            progress = False
            for thread in list(self.threads):
                if self.finished:
                    break
                held_off = self.holder is not None and self.holder is not thread
                if thread.finished or thread.spent or held_off or not self._ready(thread):
                    continue
                if self.finished:
                    break
                progress = True
                self._execute(thread)
            self.threads = [t for t in self.threads if not t.finished or t is self.main]

    def _ready(self, thread):
        """Whether a waiting thread may go on now; pushes what its call evaluates to."""
        wait = thread.wait
        if wait is None:
            return True
        kind = wait[0]
        if kind == 'until':
            ready = self.time >= wait[1] - 1e-9
            value = None
        elif kind == 'sync':
            ready, value = True, None
        elif kind == 'join':
            ready, value = wait[1].finished, None
        else:
            try:
                ready = bool(wait[1].done())
            except (ValueError, RuntimeFault) as exc:
                self._fail(_as_fault(exc), thread)
                return False
            value = wait[1].result
        if ready:
            thread.wait = None
            thread.frames[-1].stack.append(value)
        return ready

    def _block(self, thread, blocking, left):
        """`thread` waits for a robot call that takes time; it has used `left` less of its budget."""
        thread.wait = ('blocking', blocking)
        thread.spent = True
        self.instructions += self.budget - left

    def _execute(self, thread):
        try:
            self._run(thread)
            interrupted = thread.spent and thread.wait is None and not thread.finished
            self.holder = thread if interrupted and thread.critical else None
        except RuntimeFault as fault:
            self._fail(fault, thread)
        except RecursionError:
            self._fail(RuntimeFault('Stack overflow'), thread)
        except PYTHON_VALUE_ERRORS as exc:
            # What Python says of a value it cannot compute with (an int too large for a float, fmod
            # of infinity, int() of a list) is the program's runtime error, never the node's.
            self._fail(_as_fault(exc), thread)

    def _run(self, thread):
        """Run one thread until it waits, ends or spends its budget."""
        left = self.budget
        frame = thread.frames[-1]
        code = frame.code
        ops, args = code.ops, code.args
        stack = frame.stack
        glob = self.globals
        while True:
            if left <= 0:
                if self.program.secondary:
                    raise RuntimeFault('Runtime is too much behind')
                thread.spent = True  # the manual: a thread that used its frame waits for the next
                self.instructions += self.budget
                return
            left -= 1
            op = ops[frame.pc]
            arg = args[frame.pc]
            frame.pc += 1
            if op == C.CONST:
                stack.append(arg)
            elif op == C.LOAD_L:
                value = frame.locals[arg[0]]
                if value is UNSET:
                    raise RuntimeFault("Variable '%s' is used before it is assigned" % arg[1])
                stack.append(value)
            elif op == C.LOAD_G:
                value = glob.get(arg, UNSET)
                if value is UNSET:
                    raise RuntimeFault("Variable '%s' is used before it is assigned" % arg)
                stack.append(value)
            elif op == C.STORE_L:
                frame.locals[arg] = values.copy(stack.pop())
            elif op == C.STORE_G:
                glob[arg] = values.copy(stack.pop())
            elif op == C.BINARY:
                b = stack.pop()
                stack.append(values.binary(arg, stack.pop(), b))
            elif op == C.JUMP:
                frame.pc = arg
            elif op == C.JUMP_FALSE:
                if not values.truth(stack.pop()):
                    frame.pc = arg
            elif op == C.INDEX:
                i = stack.pop()
                stack.append(values.index(stack.pop(), i))
            elif op == C.CALL_PURE:
                name, fn, slots, defaults = arg
                given = _take(stack, len(slots))
                params = list(defaults)
                for slot, value in zip(slots, given):
                    params[slot] = value
                try:
                    stack.append(fn(*params))
                except PYTHON_VALUE_ERRORS as exc:
                    raise _call_fault(name, given, exc)
            elif op == C.UNARY:
                value = stack.pop()
                if arg == 'neg':
                    stack.append(values.negate(value))
                elif arg == 'not':
                    stack.append(not values.truth(value, 'the operand of not'))
                elif arg == 'bool':
                    stack.append(values.truth(value, 'an operand of and/or'))
                else:
                    stack.append(values.plus(value))
            elif op == C.AND_JUMP:
                if not values.truth(stack[-1], 'an operand of and'):
                    frame.pc = arg
                else:
                    stack.pop()
            elif op == C.OR_JUMP:
                if values.truth(stack[-1], 'an operand of or'):
                    frame.pc = arg
                else:
                    stack.pop()
            elif op == C.XOR:
                b = values.truth(stack.pop(), 'an operand of xor')
                stack.append(values.truth(stack.pop(), 'an operand of xor') != b)
            elif op == C.CALL_SCRIPT:
                entry, slots = arg
                callee = entry[2]
                if len(thread.frames) >= MAX_DEPTH:
                    raise RuntimeFault('Stack overflow: more than %d nested calls' % MAX_DEPTH)
                new = _Frame(callee)
                for slot, value in zip(slots, _take(stack, len(slots))):
                    new.locals[slot] = values.copy(value)
                thread.frames.append(new)
                frame, code = new, callee
                ops, args, stack = code.ops, code.args, new.stack
            elif op == C.RETURN:
                value = stack.pop()
                thread.frames.pop()
                if not thread.frames:
                    self.instructions += self.budget - left
                    self._thread_ended(thread)
                    return
                frame = thread.frames[-1]
                code = frame.code
                ops, args, stack = code.ops, code.args, frame.stack
                stack.append(value)
            elif op == C.POP:
                stack.pop()
            elif op == C.LIST:
                stack.append(_take(stack, arg) if arg else [])
            elif op == C.POSE:
                items = _take(stack, 6)
                for item in items:
                    if not values.is_number(item):
                        raise RuntimeFault('Type error: a pose element must be a number, not %s'
                                           % values.type_name(item))
                stack.append(Pose(items))
            elif op == C.STORE_INDEX_L or op == C.STORE_INDEX_G:
                value = stack.pop()
                indices = _take(stack, arg[1])
                if op == C.STORE_INDEX_L:
                    container = frame.locals[arg[0]]
                    name = arg[2]
                else:
                    container = glob.get(arg[0], UNSET)
                    name = arg[0]
                if container is UNSET:
                    raise RuntimeFault("Variable '%s' is used before it is assigned" % name)
                for i in indices[:-1]:
                    container = values.index(container, i)
                values.store_index(container, indices[-1], value)
            elif op == C.CALL_ROBOT:
                # A call to the robot (IO, the log, its state) costs what ROBOT_CALL_COST instructions do:
                # a loop of textmsg without sync() writes at most budget / cost lines a frame.
                left -= ROBOT_CALL_COST
                name, npositional, kwnames = arg
                given = _take(stack, npositional + len(kwnames))
                positional = [values.copy(v) for v in given[:npositional]]
                named = dict((k, values.copy(v)) for k, v in zip(kwnames, given[npositional:]))
                try:
                    result = self.robot.call(name, positional, named)
                except ValueError as exc:  # the robot refuses a call with its own words
                    raise _as_fault(exc)
                except (ArithmeticError, TypeError) as exc:
                    raise _call_fault(name, given, exc)
                if isinstance(result, Blocking):
                    self._block(thread, result, left)
                    return
                stack.append(result)
            elif op == C.CALL_METHOD:
                left -= ROBOT_CALL_COST
                method, count = arg
                given = [values.copy(v) for v in _take(stack, count)]
                handle = stack.pop()
                call_method = getattr(self.robot, 'call_method', None)
                if call_method is None:
                    raise RuntimeFault('Type error: a %s has no method %s' % (values.type_name(handle), method))
                try:
                    result = call_method(handle, method, given)
                except ValueError as exc:
                    raise _as_fault(exc)
                if isinstance(result, Blocking):
                    self._block(thread, result, left)
                    return
                stack.append(result)
            elif op == C.SLEEP:
                seconds = stack.pop()
                if not values.is_number(seconds):
                    raise RuntimeFault('Type error: sleep takes a number of seconds, not %s'
                                       % values.type_name(seconds))
                thread.wait = ('until', self.time + max(0.0, float(seconds)))
                thread.spent = True
                self.instructions += self.budget - left
                return
            elif op == C.SYNC:
                thread.wait = ('sync',)
                thread.spent = True
                self.instructions += self.budget - left
                return
            elif op == C.ENTER_CRITICAL:
                thread.critical += 1
            elif op == C.EXIT_CRITICAL:
                thread.critical -= 1
            elif op == C.JUMP_IF_SET:
                if frame.locals[arg[0]] is not UNSET:
                    frame.pc = arg[1]
            elif op == C.HALT:
                self.instructions += self.budget - left
                self._end()
                return
            elif op == C.RUN:
                code_of_thread = arg[2]
                started = _Thread(code_of_thread.name, code_of_thread)
                self.threads.append(started)
                stack.append(ThreadHandle(started))
            elif op == C.JOIN or op == C.KILL:
                handle = stack.pop()
                if handle == 0 and not isinstance(handle, (bool, ThreadHandle)):
                    # A handle variable still at the 0 the drivers' programs give it before any run
                    # (ur_robot_driver's and ur_rtde's scripts kill such a thread unconditionally): no thread.
                    continue
                if not isinstance(handle, ThreadHandle):
                    raise RuntimeFault('Type error: %s takes a thread, not %s'
                                       % ('join' if op == C.JOIN else 'kill', values.type_name(handle)))
                target = handle.thread
                if op == C.KILL:
                    if target is thread:
                        self.instructions += self.budget - left
                        self._thread_ended(thread)
                        return
                    target.finished = True
                    target.frames = []
                elif not target.finished:
                    if target is thread:
                        raise RuntimeFault('a thread cannot join itself')
                    thread.wait = ('join', target)
                    self.instructions += self.budget - left
                    return
            else:
                raise RuntimeFault('internal: unknown instruction %r' % op)

    def _thread_ended(self, thread):
        thread.finished = True
        thread.frames = []
        if self.holder is thread:
            self.holder = None
        if thread is self.main:
            self._end()


def _take(stack, n):
    if not n:
        return []
    items = stack[-n:]
    del stack[-n:]
    return items


def _call_fault(name, arguments, exc):
    """The runtime error of a call whose function could not compute with its arguments: in URScript's words.

    Python's own text names its classes and operators ("'>' not supported between instances of 'str' and
    'int'"), which no robot says; what the program needs to know is the function and the types it gave.
    Python's built-in exceptions only: the package's own (a motion's, a register's) already say it."""
    if type(exc).__module__ != 'builtins':
        return _as_fault(exc)
    types = ', '.join(values.type_name(v) for v in arguments)
    if isinstance(exc, TypeError):
        return RuntimeFault('Type error: %s cannot take (%s)' % (name, types))
    return RuntimeFault('%s cannot compute with these arguments (%s)' % (name, types))


def _as_fault(exc):
    if isinstance(exc, RuntimeFault):
        return exc
    return RuntimeFault(str(exc))
