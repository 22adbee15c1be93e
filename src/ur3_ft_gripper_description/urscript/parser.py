"""URScript text to a small syntax tree, with lark and grammar.lark.

The grammar is the one home of the syntax; this module loads it (reading the
file itself, so an installed package finds it beside this module), drops the
newlines that do not end a statement, and turns lark's tree into `Node`s that carry their
line and column. Every lark option is given explicitly: the same code runs on
lark-parser 0.8.1 (Ubuntu 20.04) and lark 1.1.x (22.04, 24.04, Debian 12).
"""

import os
import re
import threading

import lark

GRAMMAR_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'grammar.lark')

try:  # lark 1.x
    from lark.exceptions import UnexpectedEOF
except ImportError:  # lark-parser 0.8: an early end is an UnexpectedToken on $END
    UnexpectedEOF = ()


# Constructs inside one another (blocks, brackets, calls, operators) past which a script is refused: the
# parser and the compiler recurse on nesting, and Python's stack, shared with the node, must hold them.
MAX_NESTING = 100
# The grammar's rules that only group the parts of the construct above them: no nesting of their own.
_GROUPING = frozenset(['start', 'block', 'elif_clause', 'else_clause', 'params', 'param', 'args', 'arg', 'kwarg',
                       'exprlist'])
# Left-associative chains, built as one operation inside the other: each operator is a level.
_CHAINS = frozenset(['or_expr', 'xor_expr', 'and_expr', 'sum', 'term', 'comparison'])

KEYWORDS = frozenset(['def', 'sec', 'thread', 'end', 'if', 'elif', 'else', 'while', 'return', 'break',
                      'continue', 'halt', 'run', 'join', 'kill', 'local', 'global', 'and', 'or', 'xor',
                      'not', 'True', 'False', 'enter_critical', 'exit_critical'])

# PolyScope's program label: "$", the line's number in the program tree, then its texts in quotes.
LABEL_FORM = re.compile(r'\$[ \t]*\d+\b')
LABEL_EXAMPLE = '$ 3 "MoveJ"'


class CompileError(ValueError):
    """A script the robot would refuse before running it: `line N: what`."""

    def __init__(self, message, line=1, column=1):
        self.line = line
        self.column = column
        self.message = message
        ValueError.__init__(self, 'line %d: %s' % (line, message))


class Node(object):
    """One construct of the script: `kind`, where it starts, and its parts."""

    __slots__ = ('kind', 'line', 'column', 'a', 'b', 'c', 'd')

    def __init__(self, kind, line, column, a=None, b=None, c=None, d=None):
        self.kind = kind
        self.line = line
        self.column = column
        self.a, self.b, self.c, self.d = a, b, c, d

    def __repr__(self):
        return 'Node(%s@%d:%d %r %r %r %r)' % (self.kind, self.line, self.column, self.a, self.b, self.c, self.d)


# Where a line ends with one of these, the statement goes on: the next line holds its operand.
_OPERAND_EXPECTED = frozenset(['=', ',', '+', '-', '*', '/', '%', '==', '!=', '<=', '>=', '<', '>', 'and', 'or',
                               'xor', 'not'])
# A token that ends an operand, and one that begins a statement: two operands are never adjacent in an
# expression, so the second begins the next statement, on the same line.
_OPERAND_ENDS = frozenset(['NUMBER', 'STRING', 'NAME'])
_CLOSERS = frozenset([')', ']', 'True', 'False'])
_STATEMENT_KEYWORDS = frozenset(['global', 'local', 'return', 'break', 'continue', 'halt', 'join', 'kill', 'if',
                                 'while', 'def', 'sec', 'thread', 'enter_critical', 'exit_critical'])


def _ends_operand(token):
    return token is not None and (token.type in _OPERAND_ENDS and token.value not in KEYWORDS
                                  or token.value in _CLOSERS)


def _begins_statement(token):
    return token.type == 'NAME' and token.value not in KEYWORDS or token.value in _STATEMENT_KEYWORDS


def _poses_or_indexes(tokens):
    """`p[` opens a pose literal, unless its brackets hold one or two expressions: then it indexes a variable
    named p, an array or a matrix (ur_rtde's control script scales a pose argument `p` by
    `p[0] = p[0] * factor`), since a pose has six."""
    tokens = iter(tokens)
    for token in tokens:
        if token.type != 'POSE_OPEN':
            yield token
            continue
        inside, depth, commas = [], 1, 0
        for inner in tokens:
            if inner.value in ('(', '[', 'p['):
                depth += 1
            elif inner.value in (')', ']'):
                depth -= 1
            elif inner.value == ',' and depth == 1:
                commas += 1
            inside.append(inner)
            if depth == 0:
                break
        if commas > 1:
            yield token
        else:
            yield lark.Token.new_borrow_pos('NAME', 'p', token)
            yield lark.Token.new_borrow_pos('LSQB', '[', token)
        for inner in _poses_or_indexes(inside):
            yield inner


class _Newlines(object):
    """Post-lexer: where a newline ends a statement, as the controller's parser reads one.

    - Inside (...) or [...], and after a token that needs an operand (`=`, `,`, an operator), a newline
      continues the statement.
    - Two statements may share a line: an operand followed by a name or a statement's keyword begins the
      next one there.
    Both are what ur_rtde's control script needs on every real controller: its register-offset injection
    leaves `global reg_offset_float = # float register offset`, then `0    global reg_offset_int = ...`
    on the next line.
    - A program label stands alone: the manual's label line has "$" as its first symbol; anywhere else
      the robot refuses it.
    """

    always_accept = ()  # lark 1.x asks a post-lexer which terminals to keep; the grammar keeps its own

    def process(self, stream):
        depth = 0
        line_start = True
        previous = None  # the last token other than a newline
        for token in _poses_or_indexes(stream):
            if token.type == 'LABEL':
                if depth:
                    raise CompileError('a program label (%s) cannot stand inside brackets' % LABEL_EXAMPLE,
                                       token.line, token.column)
                if not line_start:
                    raise CompileError('a program label (%s) must stand on a line of its own' % LABEL_EXAMPLE,
                                       token.line, token.column)
            line_start = token.type == '_NL'
            if token.type == '_NL':
                if depth or previous is not None and previous.value in _OPERAND_EXPECTED:
                    continue
                previous = None
                yield token
                continue
            if depth == 0 and _ends_operand(previous) and _begins_statement(token):
                yield lark.Token.new_borrow_pos('_NL', '\n', token)
            if token.value in ('(', '[', 'p['):
                depth += 1
            elif token.value in (')', ']'):
                depth = max(0, depth - 1)
            previous = token
            yield token


_PARSER = None
_PARSER_BUILT = threading.Lock()
# One lexer for the whole script, not lark's contextual one: that one refuses a token the parser cannot take
# next before the post-lexer has ended the statement in front of it. Named 'standard' before lark 1.0.
_BASIC_LEXER = 'basic' if int(lark.__version__.split('.')[0]) >= 1 else 'standard'


def _parser():
    global _PARSER
    with _PARSER_BUILT:  # programs arrive on several faces' threads at once
        if _PARSER is None:
            with open(GRAMMAR_FILE) as f:
                grammar = f.read()
            _PARSER = lark.Lark(grammar, parser='lalr', lexer=_BASIC_LEXER, start='start',
                                propagate_positions=True, maybe_placeholders=False,
                                keep_all_tokens=False, postlex=_Newlines(), debug=False)
    return _PARSER


def _describe(token):
    if token is None or token.type == '$END':
        return 'end of script'
    if token.type == '_NL':
        return 'end of line'
    return '"%s"' % token.value


def parse(text):
    """[Node] of the script's top-level statements; raises CompileError naming the line."""
    source = text.replace('\r\n', '\n') + '\n'
    try:
        tree = _parser().parse(source)
    except lark.exceptions.UnexpectedCharacters as exc:
        raise CompileError('unexpected character "%s"' % source[exc.pos_in_stream], exc.line, exc.column)
    except lark.exceptions.UnexpectedToken as exc:
        token = exc.token
        if token.type == '$END' or getattr(token, 'line', None) is None:
            last = max(1, len(text.rstrip().splitlines()))
            raise CompileError('unexpected end of script: a bracket or a block is not closed', last, 1)
        raise CompileError('unexpected %s' % _describe(token), token.line, token.column)
    except UnexpectedEOF:
        last = max(1, len(text.rstrip().splitlines()))
        raise CompileError('unexpected end of script: a bracket or a block is not closed', last, 1)
    _check_nesting(tree)
    return [_build(child) for child in tree.children]


def _check_nesting(tree):
    """CompileError at the first construct nested deeper than MAX_NESTING (walked without recursion)."""
    pending = [(tree, 0)]
    while pending:
        node, depth = pending.pop()
        if node.data in _CHAINS:
            depth += sum(1 for child in node.children if isinstance(child, lark.Tree)) - 1
        elif node.data not in _GROUPING:
            depth += 1
        if depth > MAX_NESTING:
            line, column = _pos(node)
            raise CompileError('nested too deeply: more than %d blocks, brackets, calls or operators inside one '
                               'another' % MAX_NESTING, line, column)
        pending.extend((child, depth) for child in node.children if isinstance(child, lark.Tree))


def _pos(item):
    if isinstance(item, lark.Token):
        return item.line, item.column
    meta = item.meta
    return getattr(meta, 'line', 1), getattr(meta, 'column', 1)


def _ident(token):
    # Where the grammar expects no keyword, the contextual lexer reads one as a NAME.
    if str(token) in KEYWORDS:
        raise CompileError('unexpected "%s"' % token, token.line, token.column)
    return str(token)


def _block(tree):
    return [_build(child) for child in tree.children]


def _build(t):
    """Node of one lark tree or token."""
    line, column = _pos(t)
    if isinstance(t, lark.Token):
        raise CompileError('unexpected "%s"' % t.value, line, column)
    kind, ch = t.data, t.children
    if kind == 'assign':
        target = _build(ch[0])
        if target.kind not in ('name', 'index'):
            raise CompileError('cannot assign to an expression', line, column)
        node = target
        while node.kind == 'index':
            node = node.a
        if node.kind != 'name':
            raise CompileError('cannot assign to an expression', line, column)
        return Node('assign', line, column, target, _build(ch[1]))
    if kind in ('local_assign', 'global_assign'):
        return Node(kind, line, column, _ident(ch[0]), _build(ch[1]))
    if kind == 'expr_stmt':
        return Node('expr', line, column, _build(ch[0]))
    if kind == 'return_stmt':
        return Node('return', line, column, _build(ch[0]) if ch else None)
    if kind in ('break_stmt', 'continue_stmt', 'halt_stmt', 'enter_critical_stmt', 'exit_critical_stmt'):
        return Node(kind[:-len('_stmt')], line, column)
    if kind == 'label':
        if not LABEL_FORM.match(str(ch[0])):
            raise CompileError('a program label is "$", its number, then its text: %s' % LABEL_EXAMPLE,
                               line, column)
        return Node('label', line, column)
    if kind in ('join_stmt', 'kill_stmt'):
        return Node(kind[:-len('_stmt')], line, column, _build(ch[0]))
    if kind == 'if_stmt':
        branches = [(_build(ch[0]), _block(ch[1]))]
        orelse = None
        for clause in ch[2:]:
            if clause.data == 'elif_clause':
                branches.append((_build(clause.children[0]), _block(clause.children[1])))
            else:
                orelse = _block(clause.children[0])
        return Node('if', line, column, branches, orelse)
    if kind == 'while_stmt':
        return Node('while', line, column, _build(ch[0]), _block(ch[1]))
    if kind == 'funcdef':
        params = []
        body = ch[-1]
        if len(ch) == 3:
            for p in ch[1].children:
                default = _build(p.children[1]) if len(p.children) > 1 else None
                params.append((_ident(p.children[0]), default))
        names = [p for p, _ in params]
        if len(set(names)) != len(names):
            raise CompileError('function %s names a parameter twice' % ch[0], line, column)
        return Node('def', line, column, _ident(ch[0]), params, _block(body))
    if kind in ('secdef', 'threaddef'):
        return Node('sec' if kind == 'secdef' else 'thread', line, column, _ident(ch[0]), [], _block(ch[1]))
    # Expressions.
    if kind == 'number':
        text = str(ch[0])
        if '.' in text or 'e' in text or 'E' in text:
            return Node('const', line, column, float(text))
        return Node('const', line, column, int(text))
    if kind == 'string':
        return Node('const', line, column, str(ch[0])[1:-1])
    if kind == 'true':
        return Node('const', line, column, True)
    if kind == 'false':
        return Node('const', line, column, False)
    if kind == 'name':
        return Node('name', line, column, _ident(ch[0]))
    if kind == 'call':
        args, kwargs = [], []
        if len(ch) > 1:
            for arg in ch[1].children:
                if arg.data == 'kwarg':
                    if kwargs and str(arg.children[0]) in [k for k, _ in kwargs]:
                        raise CompileError('argument %s given twice' % arg.children[0], *_pos(arg))
                    kwargs.append((_ident(arg.children[0]), _build(arg.children[1])))
                else:
                    if kwargs:
                        raise CompileError('a positional argument follows a named one', *_pos(arg))
                    args.append(_build(arg.children[0]))
        return Node('call', line, column, _ident(ch[0]), args, kwargs)
    if kind == 'method_call':
        args = []
        for arg in (ch[2].children if len(ch) > 2 and ch[2] is not None else []):
            if arg.data == 'kwarg':
                raise CompileError('a remote procedure takes its arguments by position', *_pos(arg))
            args.append(_build(arg.children[0]))
        return Node('method', line, column, _build(ch[0]), _ident(ch[1]), args)
    if kind == 'run_thread':
        return Node('run', line, column, _ident(ch[0]))
    if kind == 'list_lit':
        return Node('list', line, column, [_build(e) for e in ch[0].children] if ch else [])
    if kind == 'pose_lit':
        items = [_build(e) for e in ch[1].children]
        if len(items) != 6:
            raise CompileError('a pose has 6 elements, not %d' % len(items), line, column)
        return Node('pose', line, column, items)
    if kind == 'index':
        return Node('index', line, column, _build(ch[0]), _build(ch[1]))
    if kind == 'matrix_index':
        # m[row, column] is the column'th entry of the row'th array: it reads and assigns as m[row][column].
        row = Node('index', line, column, _build(ch[0]), _build(ch[1]))
        return Node('index', line, column, row, _build(ch[2]))
    if kind in ('neg', 'pos'):
        return Node(kind, line, column, _build(ch[1]))
    if kind == 'not_op':
        return Node('not', line, column, _build(ch[0]))
    if kind in ('or_expr', 'xor_expr', 'and_expr'):
        op = kind[:-len('_expr')]
        node = _build(ch[0])
        for operand in ch[1:]:
            node = Node(op, line, column, node, _build(operand))
        return node
    if kind in ('sum', 'term', 'comparison'):
        node = _build(ch[0])
        for i in range(1, len(ch), 2):
            op = ch[i]
            node = Node('binop', op.line, op.column, str(op), node, _build(ch[i + 1]))
        return node
    raise CompileError('unsupported construct %s' % kind, line, column)  # grammar and builder disagree
