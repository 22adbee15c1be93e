"""export_mjcf: what it writes and its one-line errors (MuJoCo itself loads it in test/consumers)."""
import os
import xml.etree.ElementTree as ElementTree

import pytest

from conftest import EXPORT_MJCF, run_export


def export_mjcf(*args):
    return run_export(*args, command=EXPORT_MJCF)


def test_mjcf_has_the_mimic_equalities_stl_meshes_and_the_linkage_exclusions(tmp_path):
    out = tmp_path / 'ur3.xml'
    run = export_mjcf('-o', str(out))
    assert run.returncode == 0, run.stderr
    root = ElementTree.parse(str(out)).getroot()
    mimics = root.findall('equality/joint')
    assert sorted(m.get('joint2') for m in mimics) == ['finger_joint'] * 5
    files = [m.get('file') for m in root.iter('mesh')]
    assert files and all(f.endswith('.stl') and os.path.isfile(f) for f in files)
    assert all(os.path.dirname(f) == str(tmp_path / 'ur3_meshes') for f in files)
    excluded = {tuple(sorted((e.get('body1'), e.get('body2')))) for e in root.iter('exclude')}
    assert ('left_inner_finger', 'left_inner_knuckle') in excluded
    assert root.find("actuator/position[@joint='finger_joint']") is not None


def test_world_link_is_mujocos_world_body(tmp_path):
    out = tmp_path / 'world.xml'
    assert export_mjcf('--world', '-o', str(out)).returncode == 0
    root = ElementTree.parse(str(out)).getroot()
    assert [b.get('name') for b in root.find('worldbody')] == ['base_link']
    assert 'world' not in [b.get('name') for b in root.iter('body')]


def test_prefix_reaches_bodies_joints_and_exclusions(tmp_path):
    out = tmp_path / 'left.xml'
    assert export_mjcf('--prefix', 'left_', '-o', str(out)).returncode == 0
    root = ElementTree.parse(str(out)).getroot()
    names = [b.get('name') for b in root.iter('body')] + [j.get('name') for j in root.iter('joint')
                                                          if j.get('name')]
    assert names and all(n.startswith('left_') for n in names)
    assert all(e.get('body1').startswith('left_') for e in root.iter('exclude'))


@pytest.mark.parametrize('options,words', [
    (['--no-such-option', '-o', '{tmp}/m.xml'], ['unrecognized arguments: --no-such-option']),
    ([], ['-o/--output']),
    (['-o', '/proc/no/such/folder/m.xml'], ['cannot write /proc/no/such/folder/m.xml', 'give -o']),
    (['--ur-type', 'ur7', '-o', '{tmp}/m.xml'], ['config/ur7/', 'has the models ur3']),
])
def test_bad_input_is_one_line(tmp_path, options, words):
    run = export_mjcf(*[o.format(tmp=tmp_path) for o in options])
    assert run.returncode == 1 and run.stdout == ''
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('export_mjcf: error: '), run.stderr
    for word in words:
        assert word in lines[0], (word, lines[0])
    assert not os.path.exists(str(tmp_path / 'm.xml'))
