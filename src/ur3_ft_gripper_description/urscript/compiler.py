"""From syntax tree to checked, resumable code: names, scopes, calls, `sec` rules.

The code is a flat list of instructions per function, thread and program
body, for the small machine in machine.py: a thread that waits on physical
time keeps its place (frame, instruction, value stack) and goes on later.

Scopes, as the manual's scoping rules give them: variables of the program's
first scope level are global, with or without a qualifier; in a function or
thread, `local x = ...` is local, `global x = ...` global, and a variable
without either is global when the program has a global of that name and
local otherwise. Functions do not see the locals of the functions they sit
in. Parameters are locals.

Critical sections (`enter_critical` ... `exit_critical`) open and close in
the same block, so that every path through the code closes what it opened;
`break`, `continue` and `return` close the sections they leave. Program
labels (`$ 3 "MoveJ"`) give no code: the robot only reports them.
"""

from . import functions
from .parser import CompileError

# Instructions: (opcode, argument); lines and columns beside them.
(CONST, LOAD_L, LOAD_G, STORE_L, STORE_G, BINARY, UNARY, JUMP, JUMP_FALSE, AND_JUMP, OR_JUMP, XOR,
 INDEX, STORE_INDEX_L, STORE_INDEX_G, LIST, POSE, CALL_SCRIPT, CALL_PURE, CALL_ROBOT, SLEEP, SYNC,
 RETURN, POP, HALT, RUN, JOIN, KILL, JUMP_IF_SET, ENTER_CRITICAL, EXIT_CRITICAL, CALL_METHOD) = range(32)


class Code(object):
    """The instructions of one function, thread or program body."""

    def __init__(self, name, kind):
        self.name = name
        self.kind = kind  # 'program', 'def' or 'thread'
        self.ops = []
        self.args = []
        self.lines = []
        self.columns = []
        self.local_names = []
        self.slots = {}
        self.params = []  # [(name, has default)]

    def slot(self, name):
        if name not in self.slots:
            self.slots[name] = len(self.local_names)
            self.local_names.append(name)
        return self.slots[name]

    def emit(self, op, arg, node):
        self.ops.append(op)
        self.args.append(arg)
        self.lines.append(node.line)
        self.columns.append(node.column)
        return len(self.ops) - 1

    def patch(self, at, arg):
        self.args[at] = arg

    def here(self):
        return len(self.ops)


class Program(object):
    """A compiled script: `.name` (the def's, or None for bare statements), `.secondary`."""

    def __init__(self, name, secondary, main, text):
        self.name = name
        self.secondary = secondary
        self.main = main
        self.text = text

    def __repr__(self):
        return 'Program(name=%r, secondary=%r)' % (self.name, self.secondary)


class _Scope(object):
    """A lexical level that holds definitions: the program body or a function's body."""

    def __init__(self, parent):
        self.parent = parent
        self.functions = {}
        self.threads = {}

    def find(self, table, name):
        scope = self
        while scope is not None:
            found = getattr(scope, table).get(name)
            if found is not None:
                return found
            scope = scope.parent
        return None


def _is_program_call(node, name):
    return node.kind == 'expr' and node.a.kind == 'call' and node.a.a == name and not node.a.b and not node.a.c


def program_shape(items):
    """(name, secondary, body statements) of the script's top level.

    One top-level `def`/`sec` is the program (the robot runs it once; a call
    of it right after, which some senders add, is dropped as the robot does).
    Anything else is a program of bare statements, as the robot wraps them:
    top-level defs and threads are its definitions, the rest runs in order.
    """
    items = [n for n in items if n.kind != 'label']
    kinds = [n.kind for n in items]
    if items and kinds[0] in ('def', 'sec') and (
            len(items) == 1 or (len(items) == 2 and _is_program_call(items[1], items[0].a))):
        program = items[0]
        if program.b:
            raise CompileError('the program %s takes no parameters' % program.a, program.line, program.column)
        return program.a, program.kind == 'sec', program.c
    for node in items:
        if node.kind == 'sec':
            raise CompileError('a secondary program must be the only definition at the top of the script',
                               node.line, node.column)
    return None, False, items


class Compiler(object):
    def __init__(self, served, manual):
        self.served = dict(served)
        self.manual = manual
        self.secondary = False
        self.globals = set()
        self.critical = []  # the enter_critical statements open where the code being compiled stands

    # --- first pass: definitions and global names ---------------------------------

    def declare(self, body, scope, top):
        for node in body:
            if node.kind in ('def', 'thread', 'sec'):
                if node.kind == 'sec':
                    raise CompileError('"sec" defines a program, not a function inside one', node.line, node.column)
                table = scope.functions if node.kind == 'def' else scope.threads
                if node.a in scope.functions or node.a in scope.threads:
                    raise CompileError('%s is defined twice' % node.a, node.line, node.column)
                inner = _Scope(scope)
                table[node.a] = [node, inner, None]
                self.declare(node.c, inner, False)
            elif node.kind in ('assign', 'local_assign', 'global_assign'):
                name = node.a if node.kind != 'assign' else _target_name(node.a)
                if top or node.kind == 'global_assign':
                    self.globals.add(name)
            elif node.kind == 'if':
                for _, block in node.a:
                    self.declare(block, scope, top)
                if node.b:
                    self.declare(node.b, scope, top)
            elif node.kind == 'while':
                self.declare(node.b, scope, top)

    def locals_of(self, body, code, params):
        """The local variable names of a function or thread body (nested defs excluded)."""
        names = set(params)
        explicit_globals = set()

        def walk(block):
            for node in block:
                if node.kind == 'local_assign':
                    if node.a in explicit_globals:
                        raise CompileError('%s is global here already' % node.a, node.line, node.column)
                    names.add(node.a)
                elif node.kind == 'global_assign':
                    if node.a in names and node.a not in self.globals:
                        raise CompileError('%s is local here already' % node.a, node.line, node.column)
                    explicit_globals.add(node.a)
                elif node.kind == 'assign':
                    name = _target_name(node.a)
                    if name not in self.globals and name not in explicit_globals:
                        names.add(name)
                elif node.kind == 'if':
                    for _, inner in node.a:
                        walk(inner)
                    if node.b:
                        walk(node.b)
                elif node.kind == 'while':
                    walk(node.b)
        walk(body)
        # `local` wins over a global of the same name; a parameter is always local.
        return names - (explicit_globals - set(params))

    # --- code -----------------------------------------------------------------------

    def compile_body(self, code, body, scope, local_names):
        for name in sorted(local_names):
            code.slot(name)
        self.code, self.scope, self.local_names, self.loops, self.critical = code, scope, local_names, [], []
        self.block(body)
        code.emit(CONST, None, _last(body, code))
        code.emit(RETURN, None, _last(body, code))

    def function(self, entry):
        node, scope, code = entry
        if code is not None:
            return code
        kind = 'def' if node.kind == 'def' else 'thread'
        code = Code(node.a, kind)
        entry[2] = code
        params = [p for p, _ in node.b]
        for p in params:
            code.slot(p)
        code.params = [(p, default is not None) for p, default in node.b]
        saved = (self.code, self.scope, self.local_names, self.loops, self.critical)
        local_names = self.locals_of(node.c, code, params)
        for name in sorted(local_names):
            code.slot(name)
        self.code, self.scope, self.local_names, self.loops, self.critical = code, scope, local_names, [], []
        for p, default in node.b:
            if default is not None:
                jump = code.emit(JUMP_IF_SET, None, default)
                self.expr(default)
                code.emit(STORE_L, code.slot(p), default)
                code.patch(jump, (code.slot(p), code.here()))
        self.block(node.c)
        code.emit(CONST, None, _last(node.c, node))
        code.emit(RETURN, None, _last(node.c, node))
        self.code, self.scope, self.local_names, self.loops, self.critical = saved
        return code

    def compile_definitions(self, scope):
        for table in (scope.functions, scope.threads):
            for name in sorted(table):
                entry = table[name]
                self.function(entry)
                self.compile_definitions(entry[1])

    def block(self, body):
        opened = len(self.critical)
        for node in body:
            if node.kind == 'exit_critical' and len(self.critical) == opened:
                raise CompileError('exit_critical without an enter_critical before it in its block',
                                   node.line, node.column)
            self.statement(node)
        if len(self.critical) > opened:
            unclosed = self.critical[opened]
            raise CompileError('enter_critical without an exit_critical after it in its block',
                               unclosed.line, unclosed.column)

    def close_critical(self, down_to, node):
        """Code closing the critical sections a jump out of them leaves."""
        for _ in range(len(self.critical) - down_to):
            self.code.emit(EXIT_CRITICAL, None, node)

    def statement(self, node):
        code = self.code
        kind = node.kind
        if kind in ('def', 'thread', 'label'):
            return  # compiled on their own; a label only marks the line for the pendant
        if kind == 'enter_critical':
            self.critical.append(node)
            code.emit(ENTER_CRITICAL, None, node)
        elif kind == 'exit_critical':
            self.critical.pop()
            code.emit(EXIT_CRITICAL, None, node)
        elif kind == 'expr':
            self.expr(node.a)
            code.emit(POP, None, node)
        elif kind in ('assign', 'local_assign', 'global_assign'):
            if kind == 'assign' and node.a.kind == 'index':
                self.store_index(node.a, node.b, node)
            else:
                name = node.a if kind != 'assign' else node.a.a
                self.expr(node.b)
                self.store(name, node, kind)
        elif kind == 'if':
            ends = []
            for condition, body in node.a:
                self.expr(condition)
                skip = code.emit(JUMP_FALSE, None, condition)
                self.block(body)
                ends.append(code.emit(JUMP, None, node))
                code.patch(skip, code.here())
            if node.b:
                self.block(node.b)
            for at in ends:
                code.patch(at, code.here())
        elif kind == 'while':
            top = code.here()
            self.expr(node.a)
            leave = code.emit(JUMP_FALSE, None, node.a)
            self.loops.append((top, [], len(self.critical)))
            self.block(node.b)
            code.emit(JUMP, top, node)
            _, breaks, _ = self.loops.pop()
            for at in [leave] + breaks:
                code.patch(at, code.here())
        elif kind in ('break', 'continue'):
            if not self.loops:
                raise CompileError('"%s" outside a loop' % kind, node.line, node.column)
            self.close_critical(self.loops[-1][2], node)
            if kind == 'break':
                self.loops[-1][1].append(code.emit(JUMP, None, node))
            else:
                code.emit(JUMP, self.loops[-1][0], node)
        elif kind == 'return':
            if code.kind == 'thread':
                raise CompileError('"return" in a thread', node.line, node.column)
            if node.a is None:
                code.emit(CONST, None, node)
            else:
                if code.kind == 'program':
                    raise CompileError('the program returns no value', node.line, node.column)
                self.expr(node.a)
            self.close_critical(0, node)
            code.emit(RETURN, None, node)
        elif kind == 'halt':
            code.emit(HALT, None, node)
        elif kind in ('join', 'kill'):
            if self.secondary:
                raise CompileError('a secondary program runs no threads', node.line, node.column)
            self.expr(node.a)
            code.emit(JOIN if kind == 'join' else KILL, None, node)
        else:
            raise CompileError('unexpected "%s"' % kind, node.line, node.column)

    def is_local(self, name):
        return self.code.kind != 'program' and name in self.local_names

    def store(self, name, node, kind='assign'):
        if self.is_local(name) and kind != 'global_assign':
            self.code.emit(STORE_L, self.code.slot(name), node)
        else:
            self.code.emit(STORE_G, name, node)

    def store_index(self, target, value, node):
        indices = []
        while target.kind == 'index':
            indices.append(target.b)
            target = target.a
        name = target.a
        if not self.is_local(name) and name not in self.globals:
            raise CompileError("name '%s' is not defined" % name, target.line, target.column)
        for index in reversed(indices):
            self.expr(index)
        self.expr(value)
        if self.is_local(name):
            self.code.emit(STORE_INDEX_L, (self.code.slot(name), len(indices), name), node)
        else:
            self.code.emit(STORE_INDEX_G, (name, len(indices)), node)

    def expr(self, node):
        code = self.code
        kind = node.kind
        if kind == 'const':
            code.emit(CONST, node.a, node)
        elif kind == 'name':
            if self.is_local(node.a):
                code.emit(LOAD_L, (code.slot(node.a), node.a), node)
            elif node.a in self.globals:
                code.emit(LOAD_G, node.a, node)
            else:
                raise CompileError("name '%s' is not defined" % node.a, node.line, node.column)
        elif kind == 'binop':
            self.expr(node.b)
            self.expr(node.c)
            code.emit(BINARY, node.a, node)
        elif kind in ('neg', 'pos', 'not'):
            self.expr(node.a)
            code.emit(UNARY, kind, node)
        elif kind in ('and', 'or'):
            self.expr(node.a)
            jump = code.emit(AND_JUMP if kind == 'and' else OR_JUMP, None, node)
            self.expr(node.b)
            code.emit(UNARY, 'bool', node.b)
            code.patch(jump, code.here())
        elif kind == 'xor':
            self.expr(node.a)
            self.expr(node.b)
            code.emit(XOR, None, node)
        elif kind == 'index':
            self.expr(node.a)
            self.expr(node.b)
            code.emit(INDEX, None, node)
        elif kind == 'list':
            for item in node.a:
                self.expr(item)
            code.emit(LIST, len(node.a), node)
        elif kind == 'pose':
            for item in node.a:
                self.expr(item)
            code.emit(POSE, 6, node)
        elif kind == 'call':
            self.call(node)
        elif kind == 'method':
            # A remote procedure (rpc_factory's handle): the program waits for the server's answer.
            if self.secondary:
                raise CompileError('a secondary program may not use physical time: %s' % node.b,
                                   node.line, node.column)
            self.expr(node.a)
            for arg in node.c:
                self.expr(arg)
            code.emit(CALL_METHOD, (node.b, len(node.c)), node)
        elif kind == 'run':
            if self.secondary:
                raise CompileError('a secondary program runs no threads', node.line, node.column)
            entry = self.scope.find('threads', node.a)
            if entry is None:
                raise CompileError("thread '%s' is not defined" % node.a, node.line, node.column)
            code.emit(RUN, entry, node)
        else:
            raise CompileError('unexpected "%s"' % kind, node.line, node.column)

    def call(self, node):
        name, args, kwargs = node.a, node.b, node.c
        code = self.code
        entry = self.scope.find('functions', name)
        if entry is not None:
            params = [p for p, _ in entry[0].b]
            required = [p for p, default in entry[0].b if default is None]
            slots = self.bind(node, params, required)
            for arg in args + [value for _, value in kwargs]:
                self.expr(arg)
            code.emit(CALL_SCRIPT, (entry, slots), node)
            return
        if name in functions.TIMED:
            if self.secondary:
                raise CompileError('a secondary program may not use physical time: %s' % name,
                                   node.line, node.column)
            params = functions.TIMED[name]
            self.bind(node, [p for p, _ in params], [p for p, d in params if d is functions.REQUIRED])
            for arg in args + [value for _, value in kwargs]:
                self.expr(arg)
            code.emit(SLEEP if name == 'sleep' else SYNC, None, node)
            return
        if name in functions.PURE:
            fn, params = functions.PURE[name]
            slots = self.bind(node, [p for p, _ in params], [p for p, d in params if d is functions.REQUIRED])
            for arg in args + [value for _, value in kwargs]:
                self.expr(arg)
            code.emit(CALL_PURE, (name, fn, slots, [d for _, d in params]), node)
            return
        if name in self.served:
            if self.secondary and self.served[name]:
                raise CompileError('a secondary program may not use physical time: %s' % name,
                                   node.line, node.column)
            for arg in args + [value for _, value in kwargs]:
                self.expr(arg)
            code.emit(CALL_ROBOT, (name, len(args), [k for k, _ in kwargs]), node)
            return
        if name in self.manual:
            raise CompileError('%s is a URScript function the simulated robot does not offer' % name,
                               node.line, node.column)
        raise CompileError("name '%s' is not defined" % name, node.line, node.column)

    def bind(self, node, params, required):
        """The parameter index each argument (positional, then named) goes to; checks the counts."""
        name, args, kwargs = node.a, node.b, node.c
        if len(args) > len(params):
            raise CompileError('%s takes at most %d arguments, not %d' % (name, len(params), len(args)),
                               node.line, node.column)
        slots = list(range(len(args)))
        for key, value in kwargs:
            if key not in params:
                raise CompileError('%s has no parameter %s' % (name, key), value.line, value.column)
            if params.index(key) in slots:
                raise CompileError('%s: %s is given twice' % (name, key), value.line, value.column)
            slots.append(params.index(key))
        missing = [p for p in required if params.index(p) not in slots]
        if missing:
            raise CompileError('%s needs %s' % (name, ', '.join(missing)), node.line, node.column)
        return slots


def _target_name(target):
    while target.kind == 'index':
        target = target.a
    return target.a


def _last(body, fallback):
    return body[-1] if body else fallback


def compile_tree(items, served, manual, text=''):
    name, secondary, body = program_shape(items)
    compiler = Compiler(served, manual)
    compiler.secondary = secondary
    scope = _Scope(None)
    compiler.declare(body, scope, True)
    main = Code(name, 'program')
    compiler.compile_body(main, body, scope, set())
    # Every function and thread is compiled, called or not: the robot checks the whole
    # text, and physical time anywhere in a sec program's text refuses it.
    compiler.compile_definitions(scope)
    return Program(name, secondary, main, text)
