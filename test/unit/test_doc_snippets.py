"""Every snippet of README.md and doc/*.md that a user would paste runs, as the page has it.

The snippets come from the Markdown files (tools/doc_snippets.py), so a page's
edit is tested:
- the xacro fragment (the macro included in a user's own model) expands with
  the real xacro and with expand_description, in a package `my_cell` made
  here the way a user makes one;
- the launch fragments (a `<param>` a user puts in a launch file) load with
  `roslaunch --dump-params`, with that `my_cell` on ROS_PACKAGE_PATH;
- each `roslaunch` command loads with `roslaunch --dump-params` (everything it
  would start is resolved and every parameter set, robot_description included,
  without starting a node), and every argument it gives is one the file declares;
- each `rosrun ... export_*` command runs and writes its file.
A user's own calibration file, named in a command ($HOME/my_robot_calibration.yaml,
my_calibration.yaml), is stood in for by ur_description's default for that model.
Every other command must be listed in NOT_RUN_HERE with where it runs or why
it cannot run here: an unlisted command fails, so a new snippet is either
tested or says why not.
"""
import json
import os
import re
import shlex
import shutil
import subprocess
import sys

import pytest
import yaml

from ur3_ft_gripper_testing.model import PACKAGE_DIR, UR_CONFIG_ROOT

SNIPPETS = json.loads(subprocess.run(
    [sys.executable, os.path.join(PACKAGE_DIR, 'tools', 'doc_snippets.py'), '--json'], stdout=subprocess.PIPE,
    universal_newlines=True, check=True).stdout)
COMMANDS = [dict(c, file=b['file']) for b in SNIPPETS if b['lang'] == 'bash' for c in b['commands']]
XML = [b for b in SNIPPETS if b['lang'] == 'xml']

# Commands the snippets name that this test does not run: (start of the command, why / where it runs).
NOT_RUN_HERE = [
    ('bash tools/quickstart', 'the quickstart itself: CI (.ci/run) runs `test` in a fresh root, test/view runs what '
                              '`view` runs, test/tools its shell'),
    ('bash bench/run', 'a benchmark, not a test (doc/benchmarks.md)'),
    ('rostest ', 'a test of the suite itself'),
    ('catkin_make run_tests', 'runs this suite'),
    ('python3 -m pytest', 'runs this suite'),
    ('python3 -c', 'MuJoCo and PyBullet are in the consumers venv: test/consumers/test_doc_snippets.py runs these '
                   'blocks'),
    ('cd ', 'the catkin workspace install (doc/install.md) needs Ubuntu 20.04 with Noetic and GitHub; '
            'test_rosdep_keys.py checks that every key resolves'),
    ('git clone', 'the same install'),
    ('vcs import', 'the same install'),
    ('rosdep install', 'the same install'),
    ('sudo apt install ros-noetic-ur-calibration', 'Noetic apt on Ubuntu 20.04'),
    ('roslaunch ur_calibration', 'ur_calibration needs the robot, and is not in this workspace'),
    ('sudo usermod', 'changes the machine'),
    ('sudo dmesg', 'needs the USB adapters'),
    ('ls -l /dev/serial/by-id', 'needs the USB adapters'),
    ('export UR3_FT_GRIPPER_UPSTREAM', 'a setting (the quickstart reads it)'),
    ('rostopic ', 'needs the running devices; test/rostest speaks the same interfaces'),
    ('rosservice ', 'needs the running devices; test/rostest speaks the same interfaces'),
    ('rosrun ur3_ft_gripper_description ur_controller_sim', 'runs until stopped: test_controller_sim.py starts it '
                                                            'so and talks to every interface'),
    ("printf 'def from_network", 'needs the simulated controller running with an address: test/rostest/'
                                 'network_faces.test sends the same program to it'),
    ("printf 'robotmode", 'needs the simulated controller running with an address: test/rostest/'
                          'network_faces.test speaks the same protocol to it'),
    ("printf 'SET ACT", 'needs the bring-up running with sim_robot_ip: test/rostest/network_faces.test speaks the '
                        "gripper URCap's protocol to it"),
    ("printf 'GET STA", 'the same'),
    ('rosrun robotiq_2f_gripper_control', "Robotiq's interactive tools, not built here (test/rostest/"
                                          "gripper_registers.test speaks their registers)"),
    ('rosrun ur3_ft_gripper_description pick_and_weigh.py', 'needs the cell on physics running: '
                                                           'test/rostest/physics_cell.test runs it'),
    ('rosrun ur3_ft_gripper_description guarded_touch.py', 'the same: test/rostest/physics_cell.test runs it'),
    ('rosrun ur3_ft_gripper_description force_mode_press.py', 'the same: test/rostest/urscript_physics.test runs '
                                                             'its press at each force'),
]
RUN_HERE = ('roslaunch ', 'rosrun ur3_ft_gripper_description export_')


def not_run_reason(command):
    for start, why in NOT_RUN_HERE:
        if command.startswith(start):
            return why
    return None


def command_id(command):
    return '%s:%d' % (command['file'], command['line'])


def test_every_command_is_run_here_or_says_where_it_runs():
    unlisted = ['%s: %s' % (command_id(c), c['text']) for c in COMMANDS
                if not c['text'].startswith(RUN_HERE) and not not_run_reason(c['text'])]
    assert not unlisted, ('commands in the docs that no test runs: run them in test_doc_snippets.py or list them '
                          'in NOT_RUN_HERE with the reason:\n' + '\n'.join(unlisted))
    assert any(c['text'].startswith('roslaunch ') for c in COMMANDS)


def ur_type_of(command):
    found = re.search(r'(?:ur_type:=|--ur-type )(\w+)', command)
    return found.group(1) if found else 'ur3'


def stand_in_calibrations(command, home, cwd):
    """Each calibration file the command names, made from ur_description's default for its model."""
    default = os.path.join(UR_CONFIG_ROOT, ur_type_of(command), 'default_kinematics.yaml')
    for name in re.findall(r'(\$HOME/[\w.]+\.yaml|(?<![/\w])[\w.]*calibration\.yaml)', command):
        path = os.path.join(home, name[len('$HOME/'):]) if name.startswith('$HOME/') else os.path.join(cwd, name)
        shutil.copy(default, path)


@pytest.fixture
def user(tmp_path):
    """A user's HOME and current folder."""
    home, cwd = tmp_path / 'home', tmp_path / 'work'
    home.mkdir()
    cwd.mkdir()
    return str(home), str(cwd)


def run_as_user(command, home, cwd, env=None):
    return subprocess.run(['bash', '-c', command], cwd=cwd, env=dict(env or os.environ, HOME=home),
                          stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, timeout=300)


ROSLAUNCH = sorted({c['text']: c for c in COMMANDS if c['text'].startswith('roslaunch ')
                    and not not_run_reason(c['text'])}.values(), key=command_id)


@pytest.mark.parametrize('command', ROSLAUNCH, ids=[command_id(c) for c in ROSLAUNCH])
def test_each_roslaunch_command_loads(command, user):
    home, cwd = user
    stand_in_calibrations(command['text'], home, cwd)
    dump = run_as_user(command['text'].replace('roslaunch ', 'roslaunch --dump-params ', 1), home, cwd)
    assert dump.returncode == 0, '%s: %s\n%s' % (command_id(command), command['text'], dump.stderr[-3000:])
    assert dump.stdout.strip(), 'roslaunch --dump-params printed nothing for %s' % command['text']
    # roslaunch ignores an argument the file does not declare: a misspelt one would load too.
    declared = run_as_user(command['text'].replace('roslaunch ', 'roslaunch --ros-args ', 1), home, cwd)
    assert declared.returncode == 0, declared.stderr
    names = set(re.findall(r'^  (\w+)(?: \(default|:)', declared.stdout, re.MULTILINE))
    given = set(re.findall(r'(?:^|\s)(\w+):=', command['text'].split('#')[0]))
    assert given <= names, '%s: %s does not declare %s' % (command_id(command), command['text'].split()[2],
                                                           sorted(given - names))


EXPORTS = [c for c in COMMANDS if c['text'].startswith('rosrun ur3_ft_gripper_description export_')]


@pytest.mark.parametrize('command', EXPORTS, ids=[command_id(c) for c in EXPORTS])
def test_each_export_command_writes_its_file(command, user):
    home, cwd = user
    stand_in_calibrations(command['text'], home, cwd)
    run = run_as_user(command['text'], home, cwd)
    assert run.returncode == 0, '%s: %s\n%s' % (command_id(command), command['text'], run.stderr[-3000:])
    output = shlex.split(command['text'], comments=True)
    written = os.path.join(cwd, output[output.index('-o') + 1])
    assert os.path.getsize(written) > 1000, '%s wrote no model' % command['text']


def xml_kind(block):
    if '<xacro:' in block['text']:
        return 'xacro'
    if re.search(r'<(param|node|include|rosparam)\b', block['text']):
        return 'launch'
    return None


def test_every_xml_snippet_is_a_xacro_or_a_launch_fragment():
    assert not [b for b in XML if xml_kind(b) is None], 'an xml snippet this test does not know how to run'
    assert any(xml_kind(b) == 'xacro' for b in XML) and any(xml_kind(b) == 'launch' for b in XML)


def make_my_cell(root, xacro_fragment):
    """The package a user makes for their cell: the fragment as urdf/cell.xacro, their calibration file."""
    cell = os.path.join(root, 'my_cell')
    os.makedirs(os.path.join(cell, 'urdf'))
    os.makedirs(os.path.join(cell, 'config'))
    with open(os.path.join(cell, 'package.xml'), 'w') as f:
        f.write('<package format="3"><name>my_cell</name><version>0.0.0</version><description>cell</description>'
                '<maintainer email="me@example.org">me</maintainer><license>BSD</license>'
                '<buildtool_depend>catkin</buildtool_depend></package>\n')
    with open(os.path.join(cell, 'urdf', 'cell.xacro'), 'w') as f:
        f.write('<?xml version="1.0"?>\n<robot xmlns:xacro="http://wiki.ros.org/xacro" name="cell">\n%s</robot>\n'
                % xacro_fragment)
    for name in re.findall(r'\$\(find my_cell\)/config/([\w.]+\.yaml)', xacro_fragment):
        shutil.copy(os.path.join(UR_CONFIG_ROOT, 'ur3', 'default_kinematics.yaml'), os.path.join(cell, 'config', name))
    return cell


def environment_with(package_root):
    env = dict(os.environ)
    env['ROS_PACKAGE_PATH'] = package_root + os.pathsep + env.get('ROS_PACKAGE_PATH', '')
    return env


XACRO_FRAGMENTS = [b for b in XML if xml_kind(b) == 'xacro']
LAUNCH_FRAGMENTS = [b for b in XML if xml_kind(b) == 'launch']


@pytest.mark.parametrize('block', XACRO_FRAGMENTS, ids=['%s:%d' % (b['file'], b['line']) for b in XACRO_FRAGMENTS])
def test_the_macro_included_in_a_users_model_expands(block, tmp_path):
    cell = make_my_cell(str(tmp_path), block['text'])
    env = environment_with(str(tmp_path))
    model = os.path.join(cell, 'urdf', 'cell.xacro')
    plain = subprocess.run(['rosrun', 'xacro', 'xacro', model], env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, universal_newlines=True, timeout=300)
    assert plain.returncode == 0, plain.stderr
    assert '<link name="left_gripper_tcp"' in plain.stdout and '<link name="world"' in plain.stdout
    expanded = subprocess.run([sys.executable, os.path.join(PACKAGE_DIR, 'scripts', 'expand_description'), model],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                              timeout=300)
    assert expanded.returncode == 0, expanded.stderr
    assert expanded.stdout.count('<link name="left_base_link"') == 1, 'one base_link: the fork\'s is removed'


@pytest.mark.parametrize('block', LAUNCH_FRAGMENTS, ids=['%s:%d' % (b['file'], b['line']) for b in LAUNCH_FRAGMENTS])
def test_each_launch_fragment_loads(block, tmp_path):
    make_my_cell(str(tmp_path), XACRO_FRAGMENTS[0]['text'])
    launch = tmp_path / 'fragment.launch'
    launch.write_text('<launch>\n%s</launch>\n' % block['text'])
    dump = subprocess.run(['roslaunch', '--dump-params', str(launch)], env=environment_with(str(tmp_path)),
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, timeout=300)
    assert dump.returncode == 0 and dump.stdout.strip(), dump.stderr[-3000:]
    name = re.search(r'<param name="(\w+)"', block['text']).group(1)
    value = [v for k, v in yaml.safe_load(dump.stdout).items() if k.endswith('/' + name)]
    assert value and value[0].lstrip().startswith('<'), 'the fragment set no XML as %s' % name


YAML = [b for b in SNIPPETS if b['lang'] == 'yaml']
# A mesh file a world snippet names (e.g. part.stl) is stood in for by a 10 mm cube.
CUBE_STL = 'solid cube\n%sendsolid cube\n' % ''.join(
    'facet normal 0 0 0\nouter loop\n%sendloop\nendfacet\n' % ''.join('vertex %g %g %g\n' % v for v in face)
    for face in [((0, 0, 0), (0.01, 0, 0), (0, 0.01, 0))])


@pytest.mark.parametrize('block', YAML, ids=['%s:%d' % (b['file'], b['line']) for b in YAML])
def test_each_yaml_snippet_is_a_world_file_the_physics_cell_reads(block, tmp_path):
    from ur3_ft_gripper_description.devices.physics.world import load_world
    for mesh in re.findall(r'mesh:\s*([\w./-]+)', block['text']):
        (tmp_path / mesh).write_text(CUBE_STL)
    world = tmp_path / 'world.yaml'
    world.write_text(block['text'])
    loaded = load_world(str(world))
    assert loaded.objects, 'a world snippet without objects'
