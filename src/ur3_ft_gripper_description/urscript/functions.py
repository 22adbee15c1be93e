"""The URScript manual's functions that need no robot: math, poses, strings, lists.

Each is a Python function of URScript values with the manual's parameters
(names, defaults) and semantics; a bad argument raises RuntimeFault with the
reason. `sleep` and `sync` are the language's too, but they take time: the
interpreter runs them (machine.py); here they only have their signatures.

Poses: the position is in metres, the orientation a rotation vector (axis
times angle, radians). The manual's definitions, as matrices T = [R p; 0 1]:
- pose_trans(a, b) = T_a * T_b (move b in the frame of a);
- pose_inv(a) = T_a^-1;
- pose_add(a, b): positions added, rotations composed R_a * R_b (base frame);
- pose_sub(a, b): its inverse, positions subtracted, R_a * R_b^T, so that
  pose_add(pose_sub(a, b), b) == a;
- interpolate_pose(a, b, alpha): position on the straight line, orientation
  on the geodesic (R_a * exp(alpha * log(R_a^T R_b)));
- point_dist: distance of the positions;
- pose_dist: the manual gives no formula, only that a pure rotation has a
  distance too; here sqrt(|dp|^2 + theta^2), theta the angle between the
  orientations (metres and radians added as numbers);
- rpy2rotvec/rotvec2rpy: roll-pitch-yaw as extrinsic X-Y-Z rotations,
  R = Rz(yaw) Ry(pitch) Rx(roll).
Matrices (values.is_matrix) as the manual's "Matrix and Array Expressions":
- inv(m): a square, non-singular matrix's inverse, or a pose's (pose_inv);
- transpose(m): rows become columns. An array is a column in matrix * array,
  so its transpose is the one-row matrix: transpose(a) * b is a's dot product
  with b, as an array of one number.
Only transforms3d functions that 0.3.1 (Ubuntu 20.04) has are used.
"""

import math
import random as _random

import numpy as np
from transforms3d import axangles, euler

from .values import Pose, RuntimeFault, is_array, is_matrix, is_number, to_str, type_name, format_number

REQUIRED = object()


def _number(value, what):
    if not is_number(value):
        raise RuntimeFault('Type error: %s must be a number, not %s' % (what, type_name(value)))
    return value


def _pose(value, what='the pose'):
    if not isinstance(value, list) or len(value) != 6 or not all(is_number(v) for v in value):
        raise RuntimeFault('Type error: %s must be a pose, not %s' % (what, type_name(value)))
    return value


def _vector(value, what, size=None):
    if not isinstance(value, list) or not all(is_number(v) for v in value) or \
            (size is not None and len(value) != size):
        raise RuntimeFault('Type error: %s must be a list of %s numbers' % (what, size or 'only'))
    return np.array(value, dtype=float)


# --- rotations -----------------------------------------------------------------------

def _finite_rotation(values):
    if not np.all(np.isfinite(values)):
        # An infinite or NaN angle (a pose element, alpha) has no rotation; numpy's eigenvectors refuse it.
        raise RuntimeFault('the rotation is not finite: an angle or a pose element is infinite or NaN')
    return values


def rotvec_to_matrix(rotvec):
    rotvec = _finite_rotation(np.asarray(rotvec, dtype=float))
    angle = float(np.linalg.norm(rotvec))
    if angle < 1e-12:
        return np.eye(3)
    return axangles.axangle2mat(rotvec / angle, angle)


def matrix_to_rotvec(matrix):
    axis, angle = axangles.mat2axangle(_finite_rotation(matrix))
    if abs(angle) < 1e-12:
        return np.zeros(3)
    return np.asarray(axis, dtype=float) * angle


def pose_to_matrix(pose):
    t = np.eye(4)
    t[:3, :3] = rotvec_to_matrix(pose[3:6])
    t[:3, 3] = pose[0:3]
    return t


def matrix_to_pose(t):
    return Pose(list(t[:3, 3]) + list(matrix_to_rotvec(t[:3, :3])))


def pose_trans(p_from, p_from_to):
    return matrix_to_pose(pose_to_matrix(_pose(p_from, 'p_from')).dot(pose_to_matrix(_pose(p_from_to, 'p_from_to'))))


def pose_inv(p_from):
    return matrix_to_pose(np.linalg.inv(pose_to_matrix(_pose(p_from, 'p_from'))))


def pose_add(p_1, p_2):
    _pose(p_1, 'p_1'), _pose(p_2, 'p_2')
    rotation = rotvec_to_matrix(p_1[3:6]).dot(rotvec_to_matrix(p_2[3:6]))
    return Pose([a + b for a, b in zip(p_1[:3], p_2[:3])] + list(matrix_to_rotvec(rotation)))


def pose_sub(p_to, p_from):
    _pose(p_to, 'p_to'), _pose(p_from, 'p_from')
    rotation = rotvec_to_matrix(p_to[3:6]).dot(rotvec_to_matrix(p_from[3:6]).T)
    return Pose([a - b for a, b in zip(p_to[:3], p_from[:3])] + list(matrix_to_rotvec(rotation)))


def point_dist(p_from, p_to):
    _pose(p_from, 'p_from'), _pose(p_to, 'p_to')
    return float(np.linalg.norm(np.subtract(p_to[:3], p_from[:3])))


def _relative_angle(r_from, r_to):
    return float(np.linalg.norm(matrix_to_rotvec(rotvec_to_matrix(r_from).T.dot(rotvec_to_matrix(r_to)))))


def pose_dist(p_from, p_to):
    _pose(p_from, 'p_from'), _pose(p_to, 'p_to')
    return math.sqrt(point_dist(p_from, p_to) ** 2 + _relative_angle(p_from[3:6], p_to[3:6]) ** 2)


def interpolate_pose(p_from, p_to, alpha):
    _pose(p_from, 'p_from'), _pose(p_to, 'p_to'), _number(alpha, 'alpha')
    position = [a + alpha * (b - a) for a, b in zip(p_from[:3], p_to[:3])]
    r_from = rotvec_to_matrix(p_from[3:6])
    step = matrix_to_rotvec(r_from.T.dot(rotvec_to_matrix(p_to[3:6])))
    return Pose(position + list(matrix_to_rotvec(r_from.dot(rotvec_to_matrix(alpha * step)))))


def rpy2rotvec(rpy_vector):
    roll, pitch, yaw = _vector(rpy_vector, 'rpy_vector', 3)
    return list(matrix_to_rotvec(euler.euler2mat(roll, pitch, yaw, 'sxyz')))


def rotvec2rpy(rotation_vector):
    return list(euler.mat2euler(rotvec_to_matrix(_vector(rotation_vector, 'rotation_vector', 3)), 'sxyz'))


# --- numbers ---------------------------------------------------------------------------

def _domain(name, ok):
    if not ok:
        raise RuntimeFault('%s: argument out of domain' % name)


def acos(f):
    _domain('acos', -1 <= _number(f, 'f') <= 1)
    return math.acos(f)


def asin(f):
    _domain('asin', -1 <= _number(f, 'f') <= 1)
    return math.asin(f)


def sqrt(f):
    _domain('sqrt', _number(f, 'f') >= 0)
    return math.sqrt(f)


def log(b, f):
    _number(b, 'b'), _number(f, 'f')
    _domain('log', b > 0 and f > 0 and b != 1)
    return math.log(f) / math.log(b)


def pow_(base, exponent):
    _number(base, 'base'), _number(exponent, 'exponent')
    _domain('pow', not (base < 0 and float(exponent) != int(exponent)) and not (base == 0 and exponent < 0))
    return float(base) ** exponent


def norm(a):
    if isinstance(a, bool):
        raise RuntimeFault('Type error: norm is not defined for bool')
    if isinstance(a, int):
        return abs(a)
    if isinstance(a, float):
        return math.fabs(a)
    return float(np.linalg.norm(_vector(a, 'a')))


def normalize(v):
    vector = _vector(v, 'v')
    length = float(np.linalg.norm(vector))
    if length == 0:
        raise RuntimeFault('normalize: the list is all zeros')
    return list(vector / length)


def binary_list_to_integer(l):
    if not isinstance(l, list) or not all(isinstance(b, bool) for b in l):
        raise RuntimeFault('Type error: binary_list_to_integer takes a list of bools')
    value = 0
    for i, bit in enumerate(l[:32]):
        if bit:
            value |= 1 << i
    # The 32nd bit is the sign (two's complement).
    return value - (1 << 32) if len(l) >= 32 and l[31] else value


def integer_to_binary_list(x):
    if not isinstance(x, int) or isinstance(x, bool):
        raise RuntimeFault('Type error: integer_to_binary_list takes an int, not %s' % type_name(x))
    return [bool((x >> i) & 1) for i in range(32)]


def _int_of(f, rounding):
    _number(f, 'f')
    if isinstance(f, float) and (math.isnan(f) or math.isinf(f)):
        raise RuntimeFault('%s: argument out of domain' % rounding.__name__)
    return int(rounding(f))


# --- matrices -------------------------------------------------------------------------

def inv(m):
    if isinstance(m, Pose):
        return pose_inv(m)
    if not is_matrix(m):
        raise RuntimeFault('Type error: inv takes a matrix or a pose, not %s' % type_name(m))
    if len(m) != len(m[0]):
        raise RuntimeFault('inv: the matrix must be square, not %dx%d' % (len(m), len(m[0])))
    matrix = np.array(m, dtype=float)
    if not np.all(np.isfinite(matrix)) or np.linalg.matrix_rank(matrix) < len(m):
        raise RuntimeFault('inv: the matrix is singular')
    return np.linalg.inv(matrix).tolist()


def transpose(m):
    if is_matrix(m):
        return [list(column) for column in zip(*m)]
    if is_array(m) and m:
        return [list(m)]
    raise RuntimeFault('Type error: transpose takes a matrix or an array, not %s' % type_name(m))


# --- lists and strings -----------------------------------------------------------------

def get_list_length(v):
    if not isinstance(v, list):
        raise RuntimeFault('Type error: get_list_length takes a list, not %s' % type_name(v))
    return len(v)


def length(v):
    if not isinstance(v, (list, str)):
        raise RuntimeFault('Type error: length takes a list or a string, not %s' % type_name(v))
    return len(v)


def size(v):
    if isinstance(v, list) and v and all(isinstance(row, list) and not isinstance(row, Pose) for row in v):
        return [len(v), len(v[0])]
    return length(v)


def make_list(length, initial_value, capacity=None):
    if not isinstance(length, int) or isinstance(length, bool) or length < 0:
        raise RuntimeFault('make_list: length must be an int >= 0')
    from .values import copy
    return [copy(initial_value) for _ in range(length)]


def _string(value, what):
    if not isinstance(value, str):
        raise RuntimeFault('Type error: %s must be a string, not %s' % (what, type_name(value)))
    return value


def _bytes(value, what):
    return _string(value, what).encode('utf-8')


def str_at(src, index):
    data = _bytes(src, 'src')
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < len(data):
        raise RuntimeFault('str_at: index out of bounds')
    return data[index:index + 1].decode('utf-8', 'replace')


def _str_value(op, what):
    if isinstance(op, (str, bool)) or is_number(op):
        return to_str(op)
    if isinstance(op, list) and all(isinstance(v, (bool, Pose)) or is_number(v) for v in op):
        return to_str(op)
    raise RuntimeFault('Type error: %s cannot be a %s' % (what, type_name(op)))


def _limit(text):
    if len(text.encode('utf-8')) > 1023:
        raise RuntimeFault('string longer than 1023 characters')
    return text


def str_cat(op1, op2):
    return _limit(_str_value(op1, 'op1') + _str_value(op2, 'op2'))


def to_str_(val):
    return _limit(_str_value(val, 'val'))


def str_empty(str):
    return len(_string(str, 'str')) == 0


def str_find(src, target, start_from=0):
    data, wanted = _bytes(src, 'src'), _bytes(target, 'target')
    if not isinstance(start_from, int) or isinstance(start_from, bool) or start_from < 0:
        raise RuntimeFault('str_find: start_from out of bounds')
    return data.find(wanted, start_from)


def str_len(str):
    return len(_bytes(str, 'str'))


def str_sub(src, index, len=None):
    data = _bytes(src, 'src')
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index <= data.__len__():
        raise RuntimeFault('str_sub: index out of bounds')
    if len is None:
        return data[index:].decode('utf-8', 'replace')
    if not isinstance(len, int) or isinstance(len, bool) or len < 0:
        raise RuntimeFault('str_sub: len out of bounds')
    return data[index:index + len].decode('utf-8', 'replace')


def to_num(str):
    text = _string(str, 'str').strip()
    lowered = text.lower().lstrip('+-')
    try:
        if lowered in ('inf', 'infinity', 'nan'):
            return float(text)
        if lowered.startswith('0x'):
            return int(text, 16)
        if '.' in text:
            return float(text)
        if 'e' in lowered:
            return float(text)  # an exponent without a point: the manual's "10e3"
        return int(text)
    except ValueError:
        raise RuntimeFault('to_num: "%s" is not a number' % text)


def random():
    return _random.random()


# name: (function, [(parameter, default or REQUIRED)])
PURE = {
    'acos': (acos, [('f', REQUIRED)]),
    'asin': (asin, [('f', REQUIRED)]),
    'atan': (lambda f: math.atan(_number(f, 'f')), [('f', REQUIRED)]),
    # The manual: atan2(x, y) is the arc tangent of x/y, the first argument on top.
    'atan2': (lambda x, y: math.atan2(_number(x, 'x'), _number(y, 'y')), [('x', REQUIRED), ('y', REQUIRED)]),
    'cos': (lambda f: math.cos(_number(f, 'f')), [('f', REQUIRED)]),
    'sin': (lambda f: math.sin(_number(f, 'f')), [('f', REQUIRED)]),
    'tan': (lambda f: math.tan(_number(f, 'f')), [('f', REQUIRED)]),
    'sqrt': (sqrt, [('f', REQUIRED)]),
    'log': (log, [('b', REQUIRED), ('f', REQUIRED)]),
    'pow': (pow_, [('base', REQUIRED), ('exponent', REQUIRED)]),
    'ceil': (lambda f: _int_of(f, math.ceil), [('f', REQUIRED)]),
    'floor': (lambda f: _int_of(f, math.floor), [('f', REQUIRED)]),
    'd2r': (lambda d: _number(d, 'd') / 180.0 * math.pi, [('d', REQUIRED)]),
    'r2d': (lambda r: _number(r, 'r') / math.pi * 180.0, [('r', REQUIRED)]),
    'norm': (norm, [('a', REQUIRED)]),
    'inv': (inv, [('m', REQUIRED)]),
    'transpose': (transpose, [('m', REQUIRED)]),
    'normalize': (normalize, [('v', REQUIRED)]),
    'random': (random, []),
    'binary_list_to_integer': (binary_list_to_integer, [('l', REQUIRED)]),
    'integer_to_binary_list': (integer_to_binary_list, [('x', REQUIRED)]),
    'get_list_length': (get_list_length, [('v', REQUIRED)]),
    'length': (length, [('v', REQUIRED)]),
    'size': (size, [('v', REQUIRED)]),
    'make_list': (make_list, [('length', REQUIRED), ('initial_value', REQUIRED), ('capacity', None)]),
    'pose_trans': (pose_trans, [('p_from', REQUIRED), ('p_from_to', REQUIRED)]),
    'pose_inv': (pose_inv, [('p_from', REQUIRED)]),
    'pose_add': (pose_add, [('p_1', REQUIRED), ('p_2', REQUIRED)]),
    'pose_sub': (pose_sub, [('p_to', REQUIRED), ('p_from', REQUIRED)]),
    'pose_dist': (pose_dist, [('p_from', REQUIRED), ('p_to', REQUIRED)]),
    'point_dist': (point_dist, [('p_from', REQUIRED), ('p_to', REQUIRED)]),
    'interpolate_pose': (interpolate_pose, [('p_from', REQUIRED), ('p_to', REQUIRED), ('alpha', REQUIRED)]),
    'rpy2rotvec': (rpy2rotvec, [('rpy_vector', REQUIRED)]),
    'rotvec2rpy': (rotvec2rpy, [('rotation_vector', REQUIRED)]),
    'str_at': (str_at, [('src', REQUIRED), ('index', REQUIRED)]),
    'str_cat': (str_cat, [('op1', REQUIRED), ('op2', REQUIRED)]),
    'str_empty': (str_empty, [('str', REQUIRED)]),
    'str_find': (str_find, [('src', REQUIRED), ('target', REQUIRED), ('start_from', 0)]),
    'str_len': (str_len, [('str', REQUIRED)]),
    'str_sub': (str_sub, [('src', REQUIRED), ('index', REQUIRED), ('len', None)]),
    'to_num': (to_num, [('str', REQUIRED)]),
    'to_str': (to_str_, [('val', REQUIRED)]),
}

# The language's functions that use physical time; machine.py runs them.
TIMED = {
    'sleep': [('t', REQUIRED)],
    'sync': [],
}

__all__ = ['PURE', 'TIMED', 'REQUIRED', 'format_number']
