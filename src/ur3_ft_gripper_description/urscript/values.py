"""URScript values and what the operators do to them.

Values are Python ones: int, float, bool, str, list (a URScript array) and
`Pose`, a list of six floats. `None` is what a function without `return`
gives. An operator the language does not define for its operands raises
`RuntimeFault` (the interpreter adds the line).

What the manual leaves open, decided here (each in one place below):
- `/` gives a float, also for two ints (Python 3's true division); `%` of two
  ints is an int with the sign of the dividend (C's remainder), of floats
  C's fmod. Division or remainder by zero is a runtime error.
- `+` and `-` of two poses act element by element and give a pose; the
  manual's pose arithmetic is pose_add/pose_sub/pose_trans. `+` joins two
  strings.
- Arrays (lists of numbers) and matrices (lists of equally long arrays) take
  the operations of the manual's "Matrix and Array Expressions": matrix *
  matrix and matrix * array as in linear algebra; array op array (same
  length) and array or matrix op number, either side, entry by entry, for
  + - * / %. Other list arithmetic (matrix + matrix, array * matrix, lists of
  other things) is a type error.
- and, or, xor, not and the conditions of if/while take bools only.
- Ints are Python ints (the robot's are 32-bit; overflow is not modelled).
"""

import math


class Pose(list):
    """p[x, y, z, rx, ry, rz]: metres and a rotation vector in radians."""

    def __init__(self, values=(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)):
        list.__init__(self, [float(v) for v in values])
        if len(self) != 6:
            raise ValueError('a pose has 6 elements, not %d' % len(self))

    def __repr__(self):
        return 'Pose(%s)' % list.__repr__(self)


class RuntimeFault(Exception):
    """A runtime error of the script, as the robot reports it on the primary interface.

    `str()` is ur_client_library's RuntimeExceptionMessage::toString(): what
    ur_robot_driver logs when the robot's program stops on an error.
    """

    def __init__(self, text, line=0, column=0):
        Exception.__init__(self, text)
        self.text = text
        self.line = line
        self.column = column

    def __str__(self):
        return 'RuntimeException:\nRuntime error in line %d, column %d\nError: %s' % (
            self.line, self.column, self.text)


def type_name(value):
    if isinstance(value, bool):
        return 'bool'
    if isinstance(value, int):
        return 'int'
    if isinstance(value, float):
        return 'float'
    if isinstance(value, str):
        return 'string'
    if isinstance(value, Pose):
        return 'pose'
    if isinstance(value, list):
        return 'list'
    if value is None:
        return 'none'
    return type(value).__name__


def is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def copy(value):
    """Arrays and poses are values in URScript: assignment and arguments copy them."""
    if isinstance(value, Pose):
        return Pose(value)
    if isinstance(value, list):
        return [copy(v) for v in value]
    return value


def format_number(value):
    """The manual's to_str/str_cat format: floats with 6 decimals, trailing zeros dropped."""
    if isinstance(value, float):
        if math.isnan(value):
            return 'nan'
        if math.isinf(value):
            return 'inf' if value > 0 else '-inf'
        text = '%.6f' % value
        text = text.rstrip('0').rstrip('.')
        return '0' if text == '-0' else text
    return str(value)


def to_str(value):
    """A value as text, as textmsg, to_str and str_cat write it."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        return 'True' if value else 'False'
    if is_number(value):
        return format_number(value)
    if isinstance(value, Pose):
        return 'p[' + ', '.join(format_number(v) for v in value) + ']'
    if isinstance(value, list):
        return '[' + ', '.join(to_str(v) for v in value) + ']'
    if value is None:
        return 'None'
    return str(value)


def _type_error(op, a, b=None):
    if b is None:
        return RuntimeFault('Type error: %s is not defined for %s' % (op, type_name(a)))
    return RuntimeFault('Type error: %s is not defined for %s and %s' % (op, type_name(a), type_name(b)))


def _div(a, b):
    if b == 0:
        raise RuntimeFault('Division by zero')
    return float(a) / b


def _mod(a, b):
    if b == 0:
        raise RuntimeFault('Division by zero')
    if isinstance(a, int) and isinstance(b, int):
        remainder = abs(a) % abs(b)
        return -remainder if a < 0 else remainder
    return math.fmod(a, b)


_ARITHMETIC = {
    '+': lambda a, b: a + b,
    '-': lambda a, b: a - b,
    '*': lambda a, b: a * b,
    '/': _div,
    '%': _mod,
}

_ORDER = {
    '<': lambda a, b: a < b,
    '>': lambda a, b: a > b,
    '<=': lambda a, b: a <= b,
    '>=': lambda a, b: a >= b,
}


def equal(a, b):
    if is_number(a) and is_number(b):
        return a == b
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(equal(x, y) for x, y in zip(a, b))
    return type_name(a) == type_name(b) and a == b


def is_array(value):
    """A list of numbers (not a pose): the manual's array."""
    return type(value) is list and all(is_number(v) for v in value)


def is_matrix(value):
    """A list of one or more arrays of one common, non-zero length: the manual's matrix."""
    return (type(value) is list and bool(value) and all(type(row) is list and row for row in value)
            and len(set(len(row) for row in value)) == 1 and all(is_array(row) for row in value))


def _sum_of_products(row, column):
    total = 0
    for x, y in zip(row, column):
        total = total + x * y
    return total


def _list_arithmetic(op, a, b):
    """a op b where a list takes part (see the module's notes); a type error where none applies."""
    apply = _ARITHMETIC[op]
    if is_number(b) and (is_array(a) or is_matrix(a)):
        return [apply(x, b) if is_number(x) else [apply(y, b) for y in x] for x in a]
    if is_number(a) and (is_array(b) or is_matrix(b)):
        return [apply(a, x) if is_number(x) else [apply(a, y) for y in x] for x in b]
    if is_array(a) and is_array(b):
        if len(a) != len(b):
            raise RuntimeFault('Type error: %s of arrays of lengths %d and %d' % (op, len(a), len(b)))
        return [apply(x, y) for x, y in zip(a, b)]
    if op == '*' and is_matrix(a) and (is_matrix(b) or is_array(b)):
        if is_array(b):
            if len(a[0]) != len(b):
                raise RuntimeFault('Type error: a %dx%d matrix cannot multiply an array of length %d'
                                   % (len(a), len(a[0]), len(b)))
            return [_sum_of_products(row, b) for row in a]
        if len(a[0]) != len(b):
            raise RuntimeFault('Type error: a %dx%d matrix cannot multiply a %dx%d matrix'
                               % (len(a), len(a[0]), len(b), len(b[0])))
        columns = list(zip(*b))
        return [[_sum_of_products(row, column) for column in columns] for row in a]
    raise _type_error(op, a, b)


def binary(op, a, b):
    """a op b for the arithmetic and comparison operators."""
    if op in _ARITHMETIC:
        if is_number(a) and is_number(b):
            return _ARITHMETIC[op](a, b)
        if op == '+' and isinstance(a, str) and isinstance(b, str):
            return a + b
        if isinstance(a, Pose) or isinstance(b, Pose):
            if op in '+-' and isinstance(a, Pose) and isinstance(b, Pose):
                return Pose([_ARITHMETIC[op](x, y) for x, y in zip(a, b)])
            raise _type_error(op, a, b)
        if isinstance(a, list) or isinstance(b, list):
            return _list_arithmetic(op, a, b)
        raise _type_error(op, a, b)
    if op == '==':
        return equal(a, b)
    if op == '!=':
        return not equal(a, b)
    if is_number(a) and is_number(b):
        return _ORDER[op](a, b)
    raise _type_error(op, a, b)


def negate(a):
    if is_number(a):
        return -a
    raise _type_error('-', a)


def plus(a):
    if is_number(a):
        return a
    raise _type_error('+', a)


def truth(value, what='a condition'):
    if isinstance(value, bool):
        return value
    raise RuntimeFault('Type error: %s must be a bool, not %s' % (what, type_name(value)))


def index(container, i):
    if not isinstance(container, list):
        raise RuntimeFault('Type error: a %s cannot be indexed' % type_name(container))
    if not isinstance(i, int) or isinstance(i, bool):
        raise RuntimeFault('Type error: an index must be an int, not %s' % type_name(i))
    if i < 0 or i >= len(container):
        raise RuntimeFault('Index out of bounds: index %d, length %d' % (i, len(container)))
    return container[i]


def store_index(container, i, value):
    index(container, i)
    if isinstance(container, Pose):
        if not is_number(value):
            raise RuntimeFault('Type error: a pose element must be a number, not %s' % type_name(value))
        value = float(value)
    container[i] = copy(value)
