"""World files: a bad one is one line naming the file and the field, and a good one builds the scene."""
import numpy as np
import pytest

from ur3_ft_gripper_description.devices.physics.world import WorldError, load_world
from ur3_ft_gripper_description.number_text import number_list
from ur3_ft_gripper_testing.physics import START, TABLE

BOX = """
  - name: %s
    shape: box
    size: [0.05, 0.05, 0.1]
    pose: [%s]
    mass: 0.2
    friction: 0.5
"""


def objects(*entries):
    return TABLE + 'objects:\n' + ''.join(entries)


def box(name='block', x=0.3, y=-0.15, z=0.05):
    return BOX % (name, number_list((x, y, z)))


# (id, world text, words the line must hold): the line names the entry and the field.
BAD_FIELDS = [
    ('missing_mass', objects(box().replace('    mass: 0.2\n', '')), ['objects[0] (block)', 'no mass', 'kg']),
    ('unknown_shape', objects(box().replace('shape: box', 'shape: sphere')),
     ["unknown shape 'sphere'", 'box, cylinder, mesh']),
    ('misspelt_field', objects(box().replace('mass:', 'mas:')), ["unknown field 'mas'", 'mass']),
    ('negative_mass', objects(box().replace('mass: 0.2', 'mass: -1')), ['mass=-1', '> 0']),
    ('size_of_two', objects(box().replace('[0.05, 0.05, 0.1]', '[0.05, 0.1]')), ['size=', '3 numbers']),
    ('short_pose', objects(box().replace('pose: [0.3, -0.15, 0.05]', 'pose: [0.3, 0.1]')),
     ['pose=', 'x y z']),
    ('no_friction', objects(box().replace('    friction: 0.5\n', '')), ['no friction']),
    ('missing_mesh', objects(box().replace('shape: box', 'shape: mesh').replace(
        'size: [0.05, 0.05, 0.1]', 'mesh: parts/nothing.stl')), ['mesh parts/nothing.stl does not exist']),
    ('same_name', objects(box(), box(x=0.4)), ["the name 'block' is taken", 'objects[1]']),
    ('no_name', objects(box().replace('name: block', 'shape: box')), ['objects[0]', 'no name']),
    ('table_mass', TABLE.replace('friction: 0.5', 'friction: 0.5\n  mass: 20'), ["table: unknown field 'mass'"]),
    ('unknown_section', TABLE + 'lights: []\n', ["unknown section 'lights'"]),
    ('not_a_list', TABLE + 'objects: {a: 1}\n', ['objects must be a list']),
    ('not_yaml', TABLE + 'objects: [\n', ['not YAML']),
]


@pytest.mark.parametrize('text,words', [b[1:] for b in BAD_FIELDS], ids=[b[0] for b in BAD_FIELDS])
def test_a_bad_field_is_one_line_naming_it(tmp_path, text, words):
    path = tmp_path / 'bad.yaml'
    path.write_text(text)
    with pytest.raises(WorldError) as raised:
        load_world(str(path))
    line = str(raised.value)
    assert '\n' not in line and line.startswith(str(path) + ': '), line
    for word in words:
        assert word in line, (word, line)


def test_a_missing_world_file_is_one_line(tmp_path):
    with pytest.raises(WorldError) as raised:
        load_world(str(tmp_path / 'nowhere.yaml'))
    assert 'cannot read the world file' in str(raised.value) and '\n' not in str(raised.value)


# (id, objects, words): overlaps that only the built scene shows (MuJoCo's collision detection).
OVERLAPS = [
    ('inside_the_table', [box(z=0.03)], ['objects[0] (block) is inside the table', 'mm deep', 'raise its pose z']),
    ('inside_another', [box(), box('other', x=0.32)], ['is inside objects[', 'move one of them']),
    ('inside_the_robot', [box(x=0.2986, y=0.1124 + 0.068, z=0.12)], ["inside the robot's", 'start pose']),
]


@pytest.mark.parametrize('entries,words', [o[1:] for o in OVERLAPS], ids=[o[0] for o in OVERLAPS])
def test_an_object_inside_another_body_is_one_line(make_cell, entries, words):
    with pytest.raises(WorldError) as raised:
        make_cell(objects(*entries), START)
    line = str(raised.value)
    assert '\n' not in line, line
    for word in words:
        assert word in line, (word, line)


def test_an_unreadable_mesh_is_one_line(make_cell, tmp_path):
    (tmp_path / 'broken.stl').write_text('solid nothing\nendsolid nothing\n')
    entry = box().replace('shape: box', 'shape: mesh').replace('size: [0.05, 0.05, 0.1]', 'mesh: broken.stl')
    with pytest.raises(WorldError) as raised:
        make_cell(objects(entry), START)
    assert 'MuJoCo cannot load the cell' in str(raised.value) and '\n' not in str(raised.value)


def test_every_shape_stands_where_its_pose_puts_it(make_cell, tmp_path):
    (tmp_path / 'cube.obj').write_text(
        'v 0 0 0\nv 0.04 0 0\nv 0.04 0.04 0\nv 0 0.04 0\nv 0 0 0.04\nv 0.04 0 0.04\nv 0.04 0.04 0.04\n'
        'v 0 0.04 0.04\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\n'
        'f 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n')
    text = objects(box(), """
  - name: can
    shape: cylinder
    size: [0.07, 0.11]
    pose: [0.2, -0.25, 0.055]
    mass: 0.4
    friction: 0.4
  - name: cube
    shape: mesh
    mesh: %s
    pose: [0.4, -0.3, 0.0]
    mass: 0.1
    friction: 0.4
""" % (tmp_path / 'cube.obj'))
    cell = make_cell(text, START)
    cell.step(1.0)
    assert np.allclose(cell.object_pose('block')[0], [0.3, -0.15, 0.05], atol=0.001)
    assert np.allclose(cell.object_pose('can')[0], [0.2, -0.25, 0.055], atol=0.001)
    assert np.allclose(cell.object_pose('cube')[0], [0.4, -0.3, 0.0], atol=0.001)
    assert cell.model.body_mass[cell.model.body('cube').id] == pytest.approx(0.1)
