"""tools/quickstart finds the release's table, and on any other system stops with one line naming the supported ones.

The machine's release comes from its os-release file; these tests hand the
quickstart others (UR3_FT_GRIPPER_OS_RELEASE) and check that it stops before it
installs or builds anything. The tables themselves are read through
tools/release_table.py, as the quickstart reads them.
"""
import os
import re
import subprocess

import pytest
import yaml

PKG_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
QUICKSTART = os.path.join(PKG_DIR, 'tools', 'quickstart')
RELEASE_TABLE = os.path.join(PKG_DIR, 'tools', 'release_table.py')
RELEASES = os.path.join(PKG_DIR, 'tools', 'releases')
SUPPORTED = 'use Debian 12, Debian 13, Ubuntu 20.04 with ROS Noetic'


def quickstart(tmp_path, os_release, command='view'):
    path = tmp_path / 'os-release'
    path.write_text(os_release)
    env = dict(os.environ, UR3_FT_GRIPPER_OS_RELEASE=str(path), UR3_FT_GRIPPER_WS=str(tmp_path / 'ws'))
    return subprocess.run(['bash', QUICKSTART, command], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, env=env, timeout=120)


def table(name, key):
    run = subprocess.run(['/usr/bin/python3', RELEASE_TABLE, name, key], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True, check=True)
    return run.stdout.splitlines()


def assert_one_error_line(run, *words):
    assert run.returncode == 1, run.stderr
    lines = run.stderr.splitlines()
    assert len(lines) == 1, run.stderr
    assert lines[0].startswith('quickstart: error: '), lines[0]
    for word in words:
        assert word in lines[0], (word, lines[0])


@pytest.mark.parametrize('os_release, named', [
    ('ID=fedora\nVERSION_ID=40\nPRETTY_NAME="Fedora Linux 40"\n', 'Fedora Linux 40'),
    ('ID=debian\nVERSION_ID="11"\nPRETTY_NAME="Debian GNU/Linux 11 (bullseye)"\n', 'Debian GNU/Linux 11'),
    ('ID=ubuntu\nVERSION_ID="22.04"\nPRETTY_NAME="Ubuntu 22.04.5 LTS"\n', 'Ubuntu 22.04.5 LTS'),
    ('', 'unknown'),
], ids=['fedora', 'debian-11', 'ubuntu-22.04-leg-only', 'empty'])
def test_an_unsupported_system_gets_one_line_naming_the_supported_ones(tmp_path, os_release, named):
    run = quickstart(tmp_path, os_release)
    assert_one_error_line(run, 'unsupported system: %s' % named, SUPPORTED)
    assert not (tmp_path / 'ws').exists()  # nothing was set up


def test_noetic_s_release_without_noetic_says_to_install_it(tmp_path):
    if os.path.exists('/opt/ros/noetic/setup.bash'):
        pytest.fail('this test needs a machine without /opt/ros/noetic (it runs on Debian)')
    run = quickstart(tmp_path, 'ID=ubuntu\nVERSION_ID="20.04"\nPRETTY_NAME="Ubuntu 20.04.6 LTS"\n')
    assert_one_error_line(run, 'Ubuntu 20.04 with ROS Noetic', '/opt/ros/noetic/setup.bash is missing',
                          'http://wiki.ros.org/noetic/Installation/Ubuntu')


def test_a_leg_that_does_not_exist_prints_the_usage(tmp_path):
    machine = open('/etc/os-release').read()
    run = quickstart(tmp_path, machine, 'py27')
    assert run.returncode == 2
    assert 'py38, py310, py312, py313' in run.stdout


def test_every_table_has_only_known_keys_and_what_the_quickstart_needs():
    names = sorted(os.path.splitext(f)[0] for f in os.listdir(RELEASES) if f.endswith('.yaml'))
    set_up = []
    for name in names:
        with open(os.path.join(RELEASES, name + '.yaml')) as stream:
            raw = yaml.safe_load(stream)
        if raw.get('quickstart'):
            set_up.append(name)
            assert raw['os_release'] == name.replace('-', ' '), name  # the file is named by its release
            for key in ('apt', 'ros_apt', 'programs', 'ros_programs', 'python_modules', 'venv', 'physics',
                        'consumers', 'message_packages', 'repos'):
                assert table(name, key), (name, key)
            # every apt package a program is checked against is one the release installs
            installed = set(table(name, 'apt') + table(name, 'ros_apt') + table(name, 'release_apt'))
            for line in table(name, 'programs') + table(name, 'ros_programs') + table(name, 'python_modules'):
                program, package = line.split()
                assert package in installed or package.endswith('-catkin'), (name, program, package)
        elif name != 'common':
            table(name, 'name')  # every key known (release_table.py refuses others)
    assert set_up == ['debian-12', 'debian-13', 'ubuntu-20.04']


def test_each_leg_names_its_python_and_pins_every_package_once():
    legs = subprocess.run(['/usr/bin/python3', RELEASE_TABLE, 'legs'], stdout=subprocess.PIPE,
                          universal_newlines=True, check=True).stdout.split('\n')
    legs = [line.split() for line in legs if line]
    assert [python for python, _ in legs] == ['3.8', '3.10', '3.12', '3.13']
    for python, name in legs:
        pins = table(name, 'leg.pins') + table(name, 'venv') + table(name, 'physics')
        names = [pin.split('==')[0].lower() for pin in pins]
        assert all('==' in pin for pin in pins), (name, pins)
        assert len(names) == len(set(names)), (name, sorted(n for n in names if names.count(n) > 1))
        assert 'numpy' in names, name
    newest = dict(pin.split('==') for pin in table('newest', 'leg.pins'))
    assert int(newest['numpy'].split('.')[0]) >= 2  # the leg that catches numpy 2's removals


def test_a_known_key_that_no_table_sets_is_empty():
    assert table('debian-13', 'ros_setup') == []


def test_an_unknown_table_or_key_is_one_line():
    for args in (['debian-14', 'apt'], ['debian-13', 'no_such_key']):
        run = subprocess.run(['/usr/bin/python3', RELEASE_TABLE] + args, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, universal_newlines=True)
        assert run.returncode == 2
        assert run.stderr.count('\n') == 1 and run.stderr.startswith('release_table: '), run.stderr


def test_ci_s_two_roots_run_the_cells_targets_under_both_robotiq_variants():
    # .ci/run's fresh roots: Debian 12 and Debian 13. test/variant_scope.yaml's targets run in one variant's
    # pass per machine, so the two tables must name different variants, between them every variant.
    with open(os.path.join(PKG_DIR, 'tools', 'quickstart')) as stream:
        variants = re.search(r'^ROBOTIQ_VARIANTS=\(([^)]*)\)', stream.read(), re.MULTILINE).group(1).split()
    assert sorted(table('debian-12', 'cell_tests_variant') + table('debian-13', 'cell_tests_variant')) == \
        sorted(variants)


def test_the_scope_file_names_only_targets_cmake_defines_and_files_that_exist():
    with open(os.path.join(PKG_DIR, 'test', 'variant_scope.yaml')) as stream:
        scope = yaml.safe_load(stream)
    listed = scope['cell_targets']
    with open(os.path.join(PKG_DIR, 'CMakeLists.txt')) as stream:
        cmake = stream.read()
    rostests = set(re.findall(r'add_rostest\(test/rostest/(\S+?)\)', cmake))
    pytests = set(re.findall(r'catkin_run_tests_target\(pytest (\S+) ', cmake))
    assert set(listed) == {'rostest', 'pytest'}
    assert set(listed['rostest']) <= rostests, set(listed['rostest']) - rostests
    assert set(listed['pytest']) <= pytests, set(listed['pytest']) - pytests
    # The model and what reads it stay in every pass.
    assert not {'model', 'consumers', 'view', 'bringup'} & set(listed['pytest'])
    assert not {'tf_chain.test', 'export_fk_ur5e.test', 'sim_view.test'} & set(listed['rostest'])
    missing = [name for name in scope['cell_files'] if not os.path.isfile(os.path.join(PKG_DIR, 'test', name))]
    assert not missing, 'test/variant_scope.yaml names test files that do not exist: %s' % missing
