"""The generated pages of doc/ are what tools/generate_references.py makes of their sources today."""
import os
import shutil
import subprocess
import sys

from ur3_ft_gripper_testing.model import PACKAGE_DIR

GENERATOR = os.path.join(PACKAGE_DIR, 'tools', 'generate_references.py')
REFERENCE = os.path.join(PACKAGE_DIR, 'doc', 'launch_reference.md')
REGENERATE = 'python3 tools/generate_references.py'
# roslaunch --ros-args evaluates defaults and values, and these read ur_type.
ROS_ARGS_NEED = {'sim_arm.launch': ['ur_type:=ur5e'], 'ur_ft_gripper_bringup.launch': ['ur_type:=ur5e']}


def generate(*args):
    return subprocess.run([sys.executable, GENERATOR] + list(args), stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, universal_newlines=True, timeout=60)


def test_the_generated_pages_are_up_to_date():
    run = generate('--check')
    assert run.returncode == 0, run.stderr


def test_a_stale_reference_fails_and_names_the_command_that_regenerates_it(tmp_path):
    stale = tmp_path / 'launch_reference.md'
    stale.write_text(open(REFERENCE).read().replace('Mount the 2F-140', 'Mount a 2F-85', 1))
    shutil.copy(os.path.join(PACKAGE_DIR, 'doc', 'node_parameters.md'), str(tmp_path))  # the other page: current
    run = generate('--check', '--doc-dir', str(tmp_path))
    assert run.returncode == 1
    assert run.stderr.splitlines()[-1] == (
        'generate_references: doc/launch_reference.md is stale: run `%s`' % REGENERATE), run.stderr
    assert '+| `gripper` | `true` | Mount the 2F-140' in run.stderr, 'the diff shows what changed'


def test_every_argument_of_every_launch_file_is_in_the_reference():
    # The reference lists the args that roslaunch offers, with their doc.
    text = open(REFERENCE).read()
    for name in sorted(os.listdir(os.path.join(PACKAGE_DIR, 'launch'))):
        if not name.endswith('.launch'):
            continue
        run = subprocess.run(['roslaunch', '--ros-args', 'ur3_ft_gripper_description', name] + ROS_ARGS_NEED.get(name, []),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, timeout=60)
        assert run.returncode == 0, run.stderr
        section = text.split('## %s\n' % name)[1].split('\n## ')[0]
        assert 'Optional Arguments:' in run.stdout or 'Required Arguments:' in run.stdout, run.stdout
        for line in run.stdout.splitlines():
            if line.startswith('  ') and ':' in line:
                arg = line.split()[0].rstrip(':')
                assert '| `%s` |' % arg in section, '%s: %s missing from doc/launch_reference.md' % (name, arg)


def test_an_argument_without_doc_stops_the_generator_with_one_line(tmp_path):
    launch = tmp_path / 'launch'
    launch.mkdir()
    (launch / 'a.launch').write_text('<launch>\n  <arg name="speed" default="1"/>\n</launch>\n')
    run = generate('--launch-dir', str(launch), '--doc-dir', str(tmp_path))
    assert run.returncode == 1
    assert run.stderr.splitlines() == [
        "generate_references: error: %s: arg 'speed' has no doc=: say what it does "
        "(STYLE: doc= on every launch arg)" % os.path.relpath(str(launch / 'a.launch'), PACKAGE_DIR)], run.stderr
    assert not (tmp_path / 'launch_reference.md').exists()


def test_header_comment_and_args_render_in_order(tmp_path):
    launch = tmp_path / 'launch'
    launch.mkdir()
    (launch / 'b.launch').write_text(
        '<?xml version="1.0"?>\n<!--\n  Starts <b> things.\n\n    roslaunch pkg b.launch speed:=2\n-->\n'
        '<launch>\n  <arg name="speed" default="1" doc="How fast | in m/s"/>\n  <arg name="robot_ip" doc="IP"/>\n'
        '  <arg name="fixed" value="ur3"/>\n  <include file="x.launch"><arg name="inner" value="1"/></include>\n'
        '</launch>\n')
    shutil.copy(str(launch / 'b.launch'), str(launch / 'c.launch'))
    assert generate('--launch-dir', str(launch), '--doc-dir', str(tmp_path)).returncode == 0
    section = (tmp_path / 'launch_reference.md').read_text().split('## b.launch\n')[1].split('\n## ')[0]
    assert section.strip().splitlines() == [
        'Starts &lt;b&gt; things.', '', '```bash', 'roslaunch pkg b.launch speed:=2', '```', '',
        '| argument | default | meaning |', '| --- | --- | --- |',
        '| `speed` | `1` | How fast \\| in m/s |', '| `robot_ip` | **required** | IP |', '',
        'Set by this file: `fixed` = `ur3`.']


def test_a_node_parameter_table_renders_as_a_page(tmp_path):
    # The form a node's declaration table takes (sim_params.Param's fields; a dict serves as well).
    (tmp_path / 'declared.py').write_text(
        '"""A gripper. Its second sentence is not shown."""\n'
        'class AtStartup(object):\n    shown = "`gpo_open` of ~devices_file"\n'
        "PARAMETERS = [{'name': '~rate', 'default': 50.0, 'doc': 'status rate (Hz)'},\n"
        "              {'name': '~object_width', 'default': None, 'doc': 'm between the pads | closing stops'},\n"
        "              {'name': '~physics', 'default': False, 'doc': 'on physics'},\n"
        "              {'name': '~initial_position', 'default': AtStartup(), 'doc': 'gPO at start-up'}]\n")
    env = dict(os.environ, PYTHONPATH=str(tmp_path) + os.pathsep + os.environ.get('PYTHONPATH', ''))
    run = subprocess.run([sys.executable, GENERATOR, '--doc-dir', str(tmp_path), '--node-table',
                          'robotiq2FGripper=declared:PARAMETERS'], env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True, timeout=60)
    assert run.returncode == 0, run.stderr
    page = (tmp_path / 'node_parameters.md').read_text()
    assert page.split('## robotiq2FGripper\n')[1].strip().splitlines() == [
        'A gripper. Its second sentence is not shown.', '', 'Declared in `declared` (`PARAMETERS`).', '',
        '| parameter | default | meaning |', '| --- | --- | --- |', '| `~rate` | `50.0` | status rate (Hz) |',
        '| `~object_width` | (unset) | m between the pads \\| closing stops |',
        '| `~physics` | `false` | on physics |',
        '| `~initial_position` | `gpo_open` of ~devices_file | gPO at start-up |']


def test_a_stale_node_parameter_page_fails(tmp_path):
    # A changed declaration (here: the page edited by hand instead) is caught like a stale launch reference.
    for name in ('launch_reference.md', 'node_parameters.md'):
        shutil.copy(os.path.join(PACKAGE_DIR, 'doc', name), str(tmp_path / name))
    assert generate('--check', '--doc-dir', str(tmp_path)).returncode == 0
    page = tmp_path / 'node_parameters.md'
    page.write_text(page.read_text().replace('| `~max_pose_age` | `0.5` |', '| `~max_pose_age` | `1.0` |', 1))
    run = generate('--check', '--doc-dir', str(tmp_path))
    assert run.returncode == 1
    assert run.stderr.splitlines()[-1] == (
        'generate_references: doc/node_parameters.md is stale: run `%s`' % REGENERATE), run.stderr
    assert '+| `~max_pose_age` | `0.5` |' in run.stderr, 'the diff shows what changed'
