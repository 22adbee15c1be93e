"""Bad input: one error line naming problem and fix, non-zero exit, no URDF, no traceback.

Parameter files and args that xacro reads are test_xacro_differential's: there
expand_description must stop where plain xacro stops, with xacro's words.
"""
import os
import subprocess

import pytest
import yaml

from ur3_ft_gripper_testing.model import UR_CONFIG, assert_one_line_error, run_expand
from ur3_ft_gripper_testing.rostest_helpers import free_port


def kinematics_without(tmp_path, segment):
    with open(os.path.join(UR_CONFIG, 'default_kinematics.yaml')) as f:
        data = yaml.safe_load(f)
    del data['kinematics'][segment]
    path = tmp_path / ('no_%s.yaml' % segment)
    path.write_text(yaml.safe_dump(data))
    return str(path)


@pytest.mark.parametrize('prefix', ['a b_', '1robot_', 'arm-1_', 'tool.', '/abs_'])
def test_prefix_that_is_not_a_tf_frame_name(prefix):
    # xacro takes any prefix; robot_state_publisher's frames could not be looked up.
    assert_one_line_error(run_expand('prefix:=%s' % prefix), "'%sbase_link'" % prefix, 'TF frame name')


@pytest.mark.parametrize('package', ['ur_description', 'robotiq_ft_sensor',
                                     'robotiq_2f_140_gripper_visualization'])
def test_missing_upstream_package(package, tmp_path):
    # A ROS_PACKAGE_PATH with every package the model needs but one.
    import rospkg
    rospack = rospkg.RosPack()
    for name in ('ur3_ft_gripper_description', 'ur_description', 'robotiq_ft_sensor',
                 'robotiq_2f_140_gripper_visualization'):
        if name != package:
            os.symlink(rospack.get_path(name), str(tmp_path / name))
    env = dict(os.environ, ROS_PACKAGE_PATH=str(tmp_path))
    assert_one_line_error(run_expand(env=env), package, 'not found')


def test_missing_xacro(tmp_path):
    # A xacro module that cannot be imported, ahead of the real one on sys.path.
    (tmp_path / 'xacro').mkdir()
    (tmp_path / 'xacro' / '__init__.py').write_text("raise ImportError('No module named xacro')\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ.get('PYTHONPATH', '')]))
    assert_one_line_error(run_expand(env=env), 'xacro is not installed')


def test_unknown_xacro_file():
    assert_one_line_error(run_expand('/nonexistent/cell.xacro'), 'No such file or directory', '/nonexistent/cell.xacro')


CELL = """<robot name="cell" xmlns:xacro="http://wiki.ros.org/xacro">
  <xacro:include filename="$(find ur3_ft_gripper_description)/urdf/inc/ur3_ft_gripper_macro.xacro"/>
  %s
</robot>
"""
ONE_ROBOT = '<xacro:ur3_ft_gripper prefix="%s"/>'
TREE_FAULTS = {
    # A user's cell that calls the macro twice with one prefix.
    'same prefix twice': (ONE_ROBOT % 'r1_' + ONE_ROBOT % 'r1_', ["'r1_base_link' is not unique", 'own prefix']),
    # Two robots, nothing joining them.
    'two roots': (ONE_ROBOT % 'r1_' + ONE_ROBOT % 'r2_', ['Two root links', 'one root link']),
    'dangling joint': (ONE_ROBOT % '' + '<joint name="table_joint" type="fixed"><parent link="table"/>'
                       '<child link="base_link"/></joint>', ['[table]', 'one root link']),
    'not a frame name': (ONE_ROBOT % '' + '<link name="my cell"/><joint name="cell_joint" type="fixed">'
                         '<parent link="my cell"/><child link="base_link"/></joint>', ['my cell', 'TF frame name']),
}


@pytest.mark.parametrize('fault', sorted(TREE_FAULTS))
def test_cell_that_is_not_one_urdf_tree(fault, tmp_path):
    body, words = TREE_FAULTS[fault]
    cell = tmp_path / 'cell.xacro'
    cell.write_text(CELL % body)
    assert_one_line_error(run_expand(str(cell)), *words)


def _dump_params(*args):
    return subprocess.run(['roslaunch', '--dump-params', 'ur3_ft_gripper_description',
                           'load_ur3_ft_gripper.launch'] + list(args),
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                          timeout=120)


def test_load_launch_sets_robot_description():
    run = _dump_params()
    assert run.returncode == 0, run.stderr
    assert '/robot_description' in run.stdout and 'robotiq_arg2f_base_link' in run.stdout


def _bad_launch_args(case, tmp_path):
    """roslaunch args for one kind of bad input, and the words its one error line must have."""
    if case == 'missing file':
        return ['kinematics_params:=/nonexistent/calibration.yaml'], ['No such file', '/nonexistent/calibration.yaml']
    if case == 'empty file':
        (tmp_path / 'empty.yaml').write_text('')
        return ['joint_limit_params:=%s' % (tmp_path / 'empty.yaml')], ["['joint_limits']"]
    if case == 'malformed file':
        (tmp_path / 'broken.yaml').write_text('kinematics: [shoulder: {x: 0\n')
        return ['kinematics_params:=%s' % (tmp_path / 'broken.yaml')], ['broken.yaml', 'line 1']
    if case == 'joint missing':
        return ['kinematics_params:=%s' % kinematics_without(tmp_path, 'forearm')], ["no key 'forearm'"]
    if case == 'bad prefix':
        return ['prefix:=arm-1_'], ["'arm-1_base_link'", 'TF frame name']
    if case == 'unknown ur_type':
        return ['ur_type:=ur4'], ['config/ur4/joint_limits.yaml', 'ur3, ur3e']
    raise ValueError(case)


@pytest.mark.parametrize('case', ['missing file', 'empty file', 'malformed file', 'joint missing', 'bad prefix',
                                  'unknown ur_type'])
def test_load_launch_with_bad_input_stops_before_setting_anything(case, tmp_path):
    # A real roslaunch (not --dump-params, which exits 0 on errors) on an unused
    # master port: it must stop while loading, before it starts a master or sets
    # a parameter (no half-loaded model), with the one error line and no traceback.
    args, words = _bad_launch_args(case, tmp_path)
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % free_port())
    launch = 'load_ur_ft_gripper.launch' if case == 'unknown ur_type' else 'load_ur3_ft_gripper.launch'
    run = subprocess.run(['roslaunch', 'ur3_ft_gripper_description', launch] + args,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                         env=env, timeout=120)
    assert run.returncode == 1
    errors = [line for line in run.stderr.splitlines() if line.startswith('expand_description: error: ')]
    assert len(errors) == 1, run.stderr
    for word in words:
        assert word in errors[0], (word, errors[0])
    assert 'Traceback' not in run.stderr + run.stdout
    assert 'auto-starting new master' not in run.stdout
    assert 'PARAMETERS' not in run.stdout
