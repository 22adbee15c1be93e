"""Mutated URScript programs, as a user's typo or a bad generator would make them, from a fixed seed.

The corpus is test/data/urscript (every .script under it, read when called). `mutants(seed, count,
corpus(), function_names())` makes the same list for the same seed and corpus: the unit fuzz
(test/unit/test_urscript_fuzz.py) runs them on the arm's core, and sim_clock.test sends some on
script_command to the running node.
"""
import glob
import os
import random
import re

from ur3_ft_gripper_description import urscript
from ur3_ft_gripper_description.urscript import functions as pure_functions

from .model import PACKAGE_DIR

CORPUS = os.path.join(PACKAGE_DIR, 'test', 'data', 'urscript')


TOKEN = re.compile(r'''(?P<comment>\#.*)
                      |(?P<string>"[^"\n]*"|'[^'\n]*')
                      |(?P<number>(\d+\.\d*|\.\d+|\d+)([eE][-+]?\d+)?)
                      |(?P<pose>p\[)
                      |(?P<name>[A-Za-z_][A-Za-z_0-9]*)
                      |(?P<op>==|!=|<=|>=|[-+*/%<>=])
                      |(?P<bracket>[()\[\]])
                      |(?P<punct>[,:])
                      |(?P<space>\s+)
                      |(?P<other>.)''', re.X)
KEYWORDS = ['def', 'sec', 'thread', 'end', 'if', 'elif', 'else', 'while', 'return', 'break', 'continue', 'halt',
            'run', 'join', 'kill', 'local', 'global', 'and', 'or', 'xor', 'not', 'True', 'False']
OPERATORS = ['+', '-', '*', '/', '%', '==', '!=', '<', '>', '<=', '>=', '=', 'and', 'or', 'xor', 'not']
# What a wrong number can be: zero, a sign, too big, not finite once computed, not a number at all.
NUMBERS = ['0', '0.0', '-1', '-0.5', '1e308', '1e309', '-1e308', '1e-320', '(1/0)', '(0 % 0)', '(1e308 * 10)',
           '(0 * 1e309)', '2147483648', '99999999999999999999999999', '"7"', '"abc"', 'True', '[1, 2]',
           'p[0, 0, 0, 0, 0, 0]']
INDEXES = ['-1', '6', '7', '1000', '1.5', '"0"', 'True', '[0]', 'i + 1', '2147483648']
# Statements a bad generator leaves behind.
STATEMENTS = ['while True: end', 'while True: sync() end', 'halt', 'sync()', 'sleep(1e309)', 'sleep(-1)',
              'return', 'break', 'x = x', 'local q = q[0]', 'global g = [1, [2, [3]]]', 'textmsg()',
              'def f(): return f() end', 'f()', 'thread t(): end', 'join 1', 'kill run t()']


def tokens(line):
    return [(m.lastgroup, m.group()) for m in TOKEN.finditer(line)]


def untokens(items):
    return ''.join(text for _, text in items)


def significant(items, kinds=None):
    return [i for i, (kind, text) in enumerate(items) if kind != 'space' and (kinds is None or kind in kinds)]


class Mutator(object):
    """Mutations of a program (a list of lines), each drawing from one random.Random."""

    def __init__(self, rng, functions):
        self.rng = rng
        self.functions = functions

    def mutate(self, text):
        lines = text.split('\n')
        names = sorted({t for line in lines for kind, t in tokens(line) if kind == 'name' and t not in KEYWORDS})
        for _ in range(self.rng.choice((1, 1, 1, 2, 2, 3))):
            mutation = self.rng.choice(MUTATIONS)
            lines = mutation(self, lines, names) or lines
        return '\n'.join(lines)

    def _line(self, lines, wanted=None):
        """The index of a random line with a token of `wanted` kinds (any token: None), or None."""
        candidates = [i for i, line in enumerate(lines) if significant(tokens(line), wanted)]
        return self.rng.choice(candidates) if candidates else None

    def _replace_token(self, lines, kinds, make):
        at = self._line(lines, kinds)
        if at is None:
            return None
        items = tokens(lines[at])
        i = self.rng.choice(significant(items, kinds))
        items[i] = ('other', make(items[i][1]))
        lines = list(lines)
        lines[at] = untokens(items)
        return lines

    # line-level

    def delete_line(self, lines, names):
        at = self.rng.randrange(len(lines))
        return lines[:at] + lines[at + 1:]

    def duplicate_line(self, lines, names):
        at = self.rng.randrange(len(lines))
        return lines[:at + 1] + lines[at:]

    def swap_lines(self, lines, names):
        a, b = self.rng.randrange(len(lines)), self.rng.randrange(len(lines))
        lines = list(lines)
        lines[a], lines[b] = lines[b], lines[a]
        return lines

    def drop_end(self, lines, names):
        ends = [i for i, line in enumerate(lines) if any(t == 'end' for _, t in tokens(line))]
        if not ends:
            return None
        at = self.rng.choice(ends)
        items = tokens(lines[at])
        i = self.rng.choice([i for i, (_, t) in enumerate(items) if t == 'end'])
        return lines[:at] + [untokens(items[:i] + items[i + 1:])] + lines[at + 1:]

    def insert_statement(self, lines, names):
        at = self.rng.randrange(len(lines) + 1)
        indent = re.match(r'\s*', lines[min(at, len(lines) - 1)]).group()
        return lines[:at] + [indent + self.rng.choice(STATEMENTS)] + lines[at:]

    # token-level

    def delete_token(self, lines, names):
        return self._replace_token(lines, None, lambda text: '')

    def insert_token(self, lines, names):
        pool = KEYWORDS + OPERATORS + ['(', ')', '[', ']', 'p[', ',', ':', '0', '1.5', '"s"', '#'] + names
        return self._replace_token(lines, None, lambda text: self.rng.choice(
            (text + ' ' + self.rng.choice(pool), self.rng.choice(pool) + ' ' + text)))

    def swap_operator(self, lines, names):
        operator_names = ('and', 'or', 'xor', 'not')
        at = self._line(lines, ('op', 'name'))
        if at is None:
            return None
        items = tokens(lines[at])
        ops = [i for i in significant(items, ('op', 'name')) if items[i][0] == 'op' or items[i][1] in operator_names]
        if not ops:
            return None
        i = self.rng.choice(ops)
        items[i] = ('op', ' %s ' % self.rng.choice(OPERATORS))
        return lines[:at] + [untokens(items)] + lines[at + 1:]

    def change_number(self, lines, names):
        return self._replace_token(lines, ('number',), lambda text: self.rng.choice(NUMBERS + ['-' + text]))

    def string_for_number(self, lines, names):
        return self._replace_token(lines, ('number', 'name'), lambda text: self.rng.choice(('"%s"' % text, '""')))

    def unbalance_brackets(self, lines, names):
        if self.rng.random() < 0.5:
            return self._replace_token(lines, ('bracket', 'pose'), lambda text: '')
        return self._replace_token(lines, None, lambda text: text + self.rng.choice(('(', ')', '[', ']', 'p[')))

    def change_index(self, lines, names):
        """An index a[i] becomes a wrong one; a variable without an index gets one."""
        at = self._line(lines, ('bracket',))
        if at is not None:
            items = tokens(lines[at])
            opens = [i for i, (kind, t) in enumerate(items) if t == '[' and i > 0 and items[i - 1][0] == 'name']
            for i in self.rng.sample(opens, len(opens)):
                close = _matching(items, i)
                if close is not None:
                    items[i + 1:close] = [('other', self.rng.choice(INDEXES))]
                    return lines[:at] + [untokens(items)] + lines[at + 1:]
        return self._replace_token(lines, ('name',), lambda text: '%s[%s]' % (text, self.rng.choice(INDEXES)))

    def _a_call(self, lines):
        """(line index, its tokens, the index of a function name called there) chosen at random, or None."""
        at = self._line(lines, ('name',))
        if at is None:
            return None
        items = tokens(lines[at])
        calls = [i for i in significant(items, ('name',)) if _next_significant(items, i) == '(']
        if not calls:
            return None
        return at, items, self.rng.choice(calls)

    def rename_function(self, lines, names):
        """A call calls another function of the manual (offered by the simulation or not)."""
        found = self._a_call(lines)
        if found is None:
            return None
        at, items, i = found
        items[i] = ('name', self.rng.choice(self.functions))
        return lines[:at] + [untokens(items)] + lines[at + 1:]

    def wrong_argument_count(self, lines, names):
        found = self._a_call(lines)
        if found is None:
            return None
        at, items, i = found
        open_at = significant(items[i + 1:])[0] + i + 1
        close = _matching(items, open_at)
        if close is None:
            return None
        arguments = _split_arguments(items[open_at + 1:close])
        choice = self.rng.randrange(4)
        if choice == 0 and arguments:
            del arguments[self.rng.randrange(len(arguments))]
        elif choice == 1:
            arguments.append(self.rng.choice(('0', '[0, 0, 0, 0, 0, 0]', '"x"', 'a=1', 'v=-1', 't=1e309', 'zz=0')))
        elif choice == 2:
            arguments = []
        else:
            arguments = arguments * self.rng.choice((2, 7))
        items[open_at + 1:close] = [('other', ', '.join(arguments))]
        return lines[:at] + [untokens(items)] + lines[at + 1:]

    def deep_nesting(self, lines, names):
        depth = self.rng.choice((3, 30, 300, 3000))
        if self.rng.random() < 0.25:
            # Blocks: a run of lines inside `depth` ifs, as a generator that indents forever writes them.
            depth = min(depth, 300)
            a = self.rng.randrange(len(lines))
            b = self.rng.randrange(a, len(lines)) + 1
            return lines[:a] + ['if True:'] * depth + lines[a:b] + ['end'] * depth + lines[b:]
        wrap = self.rng.choice((
            lambda t: '(' * depth + t + ')' * depth,
            lambda t: '[' * depth + t + ']' * depth,
            lambda t: '-' * depth + t,
            lambda t: 'not ' * depth + t,
            lambda t: ' + '.join([t] * depth),
            lambda t: 'norm(' * depth + t + ')' * depth,
            lambda t: 'a' * depth,
        ))
        return self._replace_token(lines, ('number', 'name', 'string'), wrap)


MUTATIONS = [Mutator.delete_line, Mutator.duplicate_line, Mutator.swap_lines, Mutator.drop_end,
             Mutator.insert_statement, Mutator.delete_token, Mutator.insert_token, Mutator.swap_operator,
             Mutator.change_number, Mutator.string_for_number, Mutator.unbalance_brackets, Mutator.change_index,
             Mutator.rename_function, Mutator.wrong_argument_count, Mutator.deep_nesting]


def _next_significant(items, i):
    later = significant(items[i + 1:])
    return items[i + 1 + later[0]][1] if later else None


def _matching(items, open_at):
    depth = 0
    for i in range(open_at, len(items)):
        text = items[i][1]
        if text in ('(', '[', 'p['):
            depth += 1
        elif text in (')', ']'):
            depth -= 1
            if depth == 0:
                return i
    return None


def _split_arguments(items):
    arguments, current, depth = [], [], 0
    for kind, text in items:
        if text in ('(', '[', 'p['):
            depth += 1
        elif text in (')', ']'):
            depth -= 1
        if text == ',' and depth == 0:
            arguments.append(untokens(current).strip())
            current = []
        else:
            current.append((kind, text))
    if untokens(current).strip():
        arguments.append(untokens(current).strip())
    return arguments


def corpus():
    paths = sorted(glob.glob(os.path.join(CORPUS, '**', '*.script'), recursive=True))
    programs = []
    for path in paths:
        with open(path) as f:
            programs.append((os.path.relpath(path, CORPUS), f.read()))
    return programs


def function_names(served=()):
    """Every function a program can name: the manual's, the robot's (`served`) and the language's own, sorted."""
    return sorted(set(urscript.MANUAL_FUNCTIONS) | set(served) | set(pure_functions.PURE))


def mutants(seed, count, programs, functions):
    """[(source file, mutant text)], the same for the same seed, corpus and function names."""
    rng = random.Random(seed)
    mutator = Mutator(rng, functions)
    made = []
    for _ in range(count):
        name, text = rng.choice(programs)
        made.append((name, mutator.mutate(text)))
    return made
