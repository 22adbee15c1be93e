"""tools/xacro_guard.py: the package stays within Noetic's xacro; newer constructs are caught."""
import os
import subprocess
import sys

import pytest

PKG_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
GUARD = os.path.join(PKG_DIR, 'tools', 'xacro_guard.py')


def guard(*args):
    run = subprocess.run([sys.executable, GUARD] + list(args), stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, universal_newlines=True)
    return run.returncode, run.stdout.splitlines()


def upstream_changelog():
    upstream = os.environ.get('UR3_FT_GRIPPER_UPSTREAM')
    assert upstream, ('UR3_FT_GRIPPER_UPSTREAM is not set: point it at the upstream data folder '
                      '(its xacro/CHANGELOG.rst is what the guard is built on)')
    path = os.path.join(upstream, 'xacro', 'CHANGELOG.rst')
    assert os.path.isfile(path), '%s not found (UR3_FT_GRIPPER_UPSTREAM)' % path
    return path


def test_the_package_passes():
    assert guard() == (0, [])


@pytest.mark.parametrize('suffix, text, needs', [
    ('.xacro', '<robot xmlns:xacro="http://ros.org/wiki/xacro"><!-- xacro:eval-comments --></robot>', '>= 1.14.13'),
    ('.xacro', '<robot xmlns:xacro="http://ros.org/wiki/xacro"><link name="${xacro.arg(\'x\')}"/></robot>',
     '>= 1.14.11'),
    ('.xacro', '<robot xmlns:xacro="http://ros.org/wiki/xacro"><link name="l${python.abs(-1)}"/></robot>',
     '>= 1.14.17'),
    ('.yaml', 'offset: !millimeters 5\n', 'xacro 2'),
])
def test_a_construct_newer_than_the_declared_floor_is_caught(tmp_path, suffix, text, needs):
    newer = tmp_path / ('newer' + suffix)
    newer.write_text(text)
    status, lines = guard(str(newer))
    assert status == 1
    assert len(lines) == 1 and 'newer%s:1:' % suffix in lines[0] and needs in lines[0], lines


def test_constructs_at_or_below_the_floor_pass(tmp_path):
    older = tmp_path / 'older.yaml'
    older.write_text('a: !degrees 90\nb: !radians pi/2\n')
    macro = tmp_path / 'older.xacro'
    macro.write_text('<robot xmlns:xacro="http://ros.org/wiki/xacro">'
                     '<xacro:property name="p" value="${xacro.load_yaml(\'older.yaml\')}"/></robot>\n')
    assert guard(str(older), str(macro)) == (0, [])


def test_every_rule_matches_xacros_changelog():
    assert guard('--changelog', upstream_changelog()) == (0, [])


def test_a_rule_the_changelog_does_not_support_is_reported(tmp_path):
    with open(upstream_changelog()) as f:
        text = f.read()
    edited = tmp_path / 'CHANGELOG.rst'
    edited.write_text(text.replace('* Expose python.abs()\n', ''))
    status, lines = guard('--changelog', str(edited))
    assert status == 1 and len(lines) == 1 and "'Expose python.abs()'" in lines[0], lines
