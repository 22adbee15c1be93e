"""Numbers written into text (number_text): numpy's scalars read back as the same numbers, under numpy 1 and 2."""
import numpy as np
import yaml

from ur3_ft_gripper_description.number_text import number, number_list
from ur3_ft_gripper_description.urscript import compile_script

# numpy's scalar types beside Python's own: numpy 2 writes the first as np.float64(0.1) under repr.
VALUES = [0.2985999999335343, np.float64(0.2985999999335343), np.float32(0.25), np.int64(-3), 2, 1e-300,
          np.float64(-0.0)]


def test_each_number_is_python_floats_shortest_text_whatever_type_holds_it():
    assert [number(v) for v in VALUES] == ['0.2985999999335343', '0.2985999999335343', '0.25', '-3.0', '2.0',
                                           '1e-300', '-0.0']
    assert [float(number(v)) for v in VALUES] == [float(v) for v in VALUES]  # reads back exactly


def test_a_list_of_numpy_scalars_reads_back_from_yaml_as_numbers():
    position = np.array([0.2986, 0.11235, 0.06])
    loaded = yaml.safe_load('pose: [%s]\nscale: %s' % (number_list(position), number_list(position[:2], ' ')))
    assert loaded['pose'] == position.tolist()
    assert loaded['scale'] == '0.2986 0.11235'  # the space-separated form of XML attributes


def test_numpy_scalars_in_a_urscript_program_compile():
    joints = np.array([0.0, -1.5707963267948966, 1.5707963267948966, -1.5707963267948966, -1.5707963267948966, 0.0])
    text = 'def p():\n  movej([%s], t=%s)\nend' % (number_list(joints), number(np.float64(2.0)))
    assert compile_script(text, {'movej': True}).name == 'p'
