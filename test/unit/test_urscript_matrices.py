"""URScript's matrices and arrays, as the e-Series manual's "Matrix and Array Expressions" define them.

The expected values are the manual's own examples (section 4 of the script
manual since software 5.9 and 3.14, and the examples of `inv`), worked out by
hand where the manual gives only the expression, and a least-squares fit
through points on a known line, as UR's article on linear algebra in
URScript solves one.
"""
import pytest

from ur3_ft_gripper_description.urscript import CompileError, RuntimeFault, compile_script

from test_urscript_language import run_to_end, script


def run(text):
    """The finished run of `text` and the lines it wrote with textmsg."""
    program, robot, _ = run_to_end(text, max_cycles=1000)
    assert program.finished
    return program, robot.log


def value_of(expression, setup=''):
    program, log = run('%sx = %s\ntextmsg(x)\n' % (setup, expression))
    assert program.error is None, program.error
    return log[0]


MANUAL_EXAMPLES = [
    # Matrix-matrix: rows of the first times columns of the second.
    ('[[1,2],[3,4],[5,6]] * [[10,20,30],[40,50,60]]', '[[90, 120, 150], [190, 260, 330], [290, 400, 510]]'),
    # Matrix-array: an array of the matrix's number of rows.
    ('[[1,2],[3,4],[5,6]] * [10,20]', '[50, 110, 170]'),
    # Array-array, index by index.
    ('[1,2,3] * [10,20,30]', '[10, 40, 90]'),
    ('[10,20,30] / [1,2,3]', '[10, 10, 10]'),
    ('[1,2,3] + [10,20,30]', '[11, 22, 33]'),
    ('[10,20,30] - [1,2,3]', '[9, 18, 27]'),
    ('[10,20,30] % [1,2,3]', '[0, 0, 0]'),
    # A scalar on every entry, on either side.
    ('[1,2,3] * 5', '[5, 10, 15]'),
    ('5 * [[1,2],[3,4],[5,6]]', '[[5, 10], [15, 20], [25, 30]]'),
    ('[10,20,30] / 10', '[1, 2, 3]'),
    ('10 / [10,20,30]', '[1, 0.5, 0.333333]'),
    # inv's examples.
    ('inv([[0,1,0],[0,0,1],[1,0,0]])', '[[0, 0, 1], [1, 0, 0], [0, 1, 0]]'),
    ('inv(p[.2,.5,.1,1.57,0,3.14])', 'p[0.193238, 0.417943, -0.296619, 1.239926, 0, 2.479852]'),
    ('transpose([[1,2],[3,4],[5,6]])', '[[1, 3, 5], [2, 4, 6]]'),
    ('size([[1,2],[3,4],[5,6]])', '[3, 2]'),
]


@pytest.mark.parametrize('expression, printed', MANUAL_EXAMPLES)
def test_the_manuals_examples(expression, printed):
    assert value_of(expression) == printed


def test_the_manuals_reads_and_writes_of_single_entries():
    _, log = run('array = [1,2,3,4,5]\na = array[0]\narray[2] = 10\n'
                 'matrix = [[1,2],[3,4],[5,6]]\nb = matrix[0,0]\nmatrix[2,1] = 20\n'
                 'textmsg(a, array)\ntextmsg(b, matrix)\n')
    assert log == ['1[1, 2, 10, 4, 5]', '1[[1, 2], [3, 4], [5, 20]]']


def test_a_least_squares_fit_finds_the_line_the_points_lie_on():
    # y = 2 x + 1 at x = 0..3: the normal equations give intercept 1 and slope 2.
    printed = value_of('inv(transpose(A) * A) * transpose(A) * y',
                       'A = [[1,0],[1,1],[1,2],[1,3]]\ny = [1,3,5,7]\n')
    assert [round(float(v), 9) for v in printed.strip('[]').split(',')] == [1.0, 2.0]


def test_the_transpose_of_an_array_times_an_array_is_their_dot_product():
    assert value_of('transpose([1,2,3]) * [4,5,6]') == '[32]'


def test_a_matrix_times_its_inverse_is_the_identity():
    printed = value_of('m * inv(m)', 'm = [[2,1,0],[1,3,1],[0,1,4]]\n')
    assert printed == '[[1, 0, 0], [0, 1, 0], [0, 0, 1]]'


def test_a_variable_named_p_is_indexed_as_a_matrix_and_a_pose_literal_still_has_six():
    _, log = run('p = [[1,2],[3,4]]\np[1,0] = 7\ntextmsg(p[1,0])\nq = p[1,2,3,0,0,0]\ntextmsg(q)\n')
    assert log == ['7', 'p[1, 2, 3, 0, 0, 0]']


RUNTIME_ERRORS = [
    ('[[1,2],[3,4]] * [[1,2,3]]', 'Type error: a 2x2 matrix cannot multiply a 1x3 matrix'),
    ('[[1,2],[3,4]] * [1,2,3]', 'Type error: a 2x2 matrix cannot multiply an array of length 3'),
    ('[1,2] + [1,2,3]', 'Type error: + of arrays of lengths 2 and 3'),
    ('[1,2] * [[1,2],[3,4]]', 'Type error: * is not defined for list and list'),
    ('[[1,2],[3,4]] + [[1,2],[3,4]]', 'Type error: + is not defined for list and list'),
    ('[[1,2],[3]] * 2', 'Type error: * is not defined for list and int'),
    ('[1,"a"] * 2', 'Type error: * is not defined for list and int'),
    ('p[1,2,3,0,0,0] * 2', 'Type error: * is not defined for pose and int'),
    ('[1,2] / [1,0]', 'Division by zero'),
    ('inv([[1,2],[2,4]])', 'inv: the matrix is singular'),
    ('inv([[1,2,3],[4,5,6]])', 'inv: the matrix must be square, not 2x3'),
    ('transpose(3)', 'Type error: transpose takes a matrix or an array, not int'),
]


@pytest.mark.parametrize('expression, text', RUNTIME_ERRORS)
def test_what_the_manual_does_not_define_stops_the_program_on_its_line(expression, text):
    program, log = run('textmsg("before")\nx = %s\ntextmsg("after")\n' % expression)
    assert isinstance(program.error, RuntimeFault)
    assert (program.error.line, program.error.text) == (2, text)
    assert log == ['before']


def test_a_pose_literal_of_other_than_six_is_still_refused_when_the_program_compiles():
    with pytest.raises(CompileError) as caught:
        compile_script('x = p[1,2,3]\n', {'textmsg': False})
    assert 'a pose has 6 elements, not 3' in str(caught.value)


def test_the_corpus_program_fits_its_line_and_turns_its_point():
    program, log = run(script('matrices.script'))
    assert program.error is None
    # y = 2 x + 1; a quarter turn about z takes (0.2, 0, 0.3) to (0, 0.2, 0.3), then 0.1 m (0.15 m) along x.
    assert log == ['intercept and slope [1, 2]', 'point [0.1, 0.2, 0.3, 1] moved [0.15, 0.2, 0.3, 1]',
                   'scaled [3, 6, 9] size [4, 4]']
