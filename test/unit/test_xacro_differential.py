"""expand_description reads parameter files and args as plain xacro does.

Each case gives the same args and parameter files to `$(find xacro)/xacro`
(the xacro that upstream launch files run) and to `expand_description`.
Where xacro expands the model, both outputs are the same URDF once the
jr-robotics fork's extra base_link is dropped (a no-op with ros-industrial's
package); where xacro stops, expand_description stops too, with one line that
holds xacro's own words for the problem.

The cases' YAML is users' input: `!millimeters` is xacro 2's, and a
Noetic xacro 1.14 that lacks it must then fail on both sides alike.
"""
import importlib.metadata
import math
import os
import subprocess
import xml.dom.minidom
import xml.etree.ElementTree as ElementTree

import pytest
import yaml
from roslaunch.substitution_args import resolve_args

from ur3_ft_gripper_description.model import description
from ur3_ft_gripper_testing.model import EXPAND, PACKAGE_DIR, UR_CONFIG, ExpandedModel, assert_one_line_error

XACRO_FILE = os.path.join(PACKAGE_DIR, 'urdf', 'ur3_ft_gripper.xacro')


def ur3_file(name, edit=None):
    """The text of ur_description's UR3 file `name`, with `edit` (old, new) applied once."""
    with open(os.path.join(UR_CONFIG, name)) as f:
        text = f.read()
    if edit:
        assert edit[0] in text, edit
        text = text.replace(edit[0], edit[1], 1)
    return text


def kinematics_without(segment):
    with open(os.path.join(UR_CONFIG, 'default_kinematics.yaml')) as f:
        data = yaml.safe_load(f)
    del data['kinematics'][segment]
    return yaml.safe_dump(data)


SHOULDER_Z = 'z: 0.1519'          # default_kinematics.yaml, shoulder
PAN_MAX = 'max_position: !degrees  360.0'  # joint_limits.yaml, shoulder_pan

EXPANDS, FAILS = 'expands', 'fails'
# Length units are xacro 2's: Noetic's xacro 1.14 refuses them, PyPI's 2.1.1 reads them.
XACRO_2_EXPANDS = EXPANDS if int(importlib.metadata.version('xacro').split('.')[0]) >= 2 else FAILS

# name: (what plain xacro does, args, {arg: parameter file text}).
CASES = {
    'defaults': (EXPANDS, [], {}),
    'another ur_type': (EXPANDS, ['ur_type:=ur5e'], {}),
    'radians expression': (EXPANDS, [], {'joint_limit_params': ur3_file('joint_limits.yaml', (PAN_MAX, 'max_position: !radians 2*pi'))}),
    'degrees expression': (EXPANDS, [], {'joint_limit_params': ur3_file('joint_limits.yaml', (PAN_MAX, 'max_position: !degrees 90 * 4'))}),
    'millimeters expression': (XACRO_2_EXPANDS, [], {'kinematics_params': ur3_file('default_kinematics.yaml', (SHOULDER_Z, 'z: !millimeters 150 + 1.9'))}),
    'radians syntax error': (FAILS, [], {'joint_limit_params': ur3_file('joint_limits.yaml', (PAN_MAX, 'max_position: !radians 2*'))}),
    'degrees unknown name': (FAILS, [], {'joint_limit_params': ur3_file('joint_limits.yaml', (PAN_MAX, 'max_position: !degrees full_turn'))}),
    'millimeters not a number': (FAILS, [], {'kinematics_params': ur3_file('default_kinematics.yaml', (SHOULDER_Z, "z: !millimeters '15a'"))}),
    'missing segment': (FAILS, [], {'kinematics_params': kinematics_without('wrist_3')}),
    'missing key': (FAILS, [], {'kinematics_params': ur3_file('default_kinematics.yaml', (SHOULDER_Z, 'height: 0.1519'))}),
    'wrong kind of file': (FAILS, [], {'kinematics_params': ur3_file('joint_limits.yaml')}),
    'empty file': (FAILS, [], {'joint_limit_params': ''}),
    'malformed YAML': (FAILS, [], {'kinematics_params': 'kinematics: [shoulder: {x: 0\n'}),
    'missing file': (FAILS, ['physical_params:=/nonexistent/physical_parameters.yaml'], {}),
    'boolean 0 and True': (EXPANDS, ['ft_sensor:=0', 'gripper:=True'], {}),
    'boolean 1 for world': (EXPANDS, ['world:=1'], {}),
    'bad boolean ft_sensor': (FAILS, ['ft_sensor:=maybe'], {}),
    'bad boolean world': (FAILS, ['world:=yes'], {}),
    'bad boolean safety_limits': (FAILS, ['safety_limits:=on'], {}),
    'unknown ur_type': (FAILS, ['ur_type:=ur4'], {}),
    'unknown ur_type in capitals': (FAILS, ['ur_type:=UR3'], {}),
}


def run(command, args):
    return subprocess.run(command + [XACRO_FILE] + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, timeout=120)


def canonical(urdf):
    """The URDF's elements and attributes, without comments and indentation."""
    return ElementTree.canonicalize(urdf, strip_text=True)


def xacro_problem(stderr):
    """xacro's first error line, without its 'error: ' and spacing."""
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert lines and lines[0].startswith('error: '), stderr
    return ' '.join(lines[0][len('error: '):].split())


@pytest.mark.parametrize('case', sorted(CASES))
def test_expand_description_reads_args_and_files_as_plain_xacro_does(case, tmp_path):
    outcome, args, files = CASES[case]
    for arg, text in files.items():
        path = tmp_path / ('%s.yaml' % arg)
        path.write_text(text)
        args = args + ['%s:=%s' % (arg, path)]
    plain = run([resolve_args('$(find xacro)/xacro')], args)
    ours = run(EXPAND, args)
    assert (EXPANDS if plain.returncode == 0 else FAILS) == outcome, plain.stderr
    if plain.returncode == 0:
        assert ours.returncode == 0, ours.stderr
        expected = xml.dom.minidom.parseString(plain.stdout)
        description.remove_forked_gripper_roots(expected)
        description.correct_for_consumers(expected)
        assert canonical(ours.stdout) == canonical(description.to_xml(expected))
    else:
        assert_one_line_error(ours, XACRO_FILE, xacro_problem(plain.stderr))


def test_the_reported_radians_case_expands_to_a_full_turn(tmp_path):
    limits = tmp_path / 'joint_limits.yaml'
    limits.write_text(CASES['radians expression'][2]['joint_limit_params'])
    ours = run(EXPAND, ['joint_limit_params:=%s' % limits])
    assert ours.returncode == 0, ours.stderr
    assert ExpandedModel(ours.stdout).limits('shoulder_pan_joint')[1] == pytest.approx(2 * math.pi)
