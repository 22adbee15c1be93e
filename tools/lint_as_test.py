#!/usr/bin/env python3
"""Run catkin_lint on the package with a rosdep database, and record it as one JUnit test case.

Usage: lint_as_test.py PACKAGE_DIR RESULT_XML

catkin_lint flags a dependency key it cannot find only when it has a rosdep
database; without one it ignores every unknown key. The database here is
rosdep's own, built offline by `rosdep update` from the rosdistro files in
$UR3_FT_GRIPPER_ROSDISTRO (base.yaml, python.yaml, noetic-distribution.yaml)
through a `yaml file://` sources list and an index of its own, in a ROS_HOME
of its own, so a user's ~/.ros and /etc/ros are neither used nor changed.
PACKAGE_DIR must be named like the package (e.g. the workspace's src/ link).
"""
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

ROSDISTRO_FILES = ('base.yaml', 'python.yaml', 'noetic-distribution.yaml')

INDEX = '''%%YAML 1.1
---
distributions:
  noetic:
    distribution: [file://%s]
    distribution_status: active
    distribution_type: ros1
    python_version: 3
type: index
version: 4
'''


def rosdep_environment(rosdistro, folder):
    """Environment for rosdep and catkin_lint with a database built from `rosdistro` in `folder`."""
    sources = os.path.join(folder, 'sources.list.d')
    os.makedirs(sources)
    with open(os.path.join(sources, '20-default.list'), 'w') as f:
        for name in ROSDISTRO_FILES[:2]:
            f.write('yaml file://%s\n' % os.path.join(rosdistro, name))
    index = os.path.join(folder, 'index.yaml')
    with open(index, 'w') as f:
        f.write(INDEX % os.path.join(rosdistro, ROSDISTRO_FILES[2]))
    return dict(os.environ, ROSDEP_SOURCE_PATH=sources, ROS_HOME=os.path.join(folder, 'ros_home'),
                ROSDISTRO_INDEX_URL='file://' + index, ROS_DISTRO='noetic', ROS_PYTHON_VERSION='3')


def lint(package_dir):
    """(passed, report) of catkin_lint -W2 --strict with the rosdep database."""
    rosdistro = os.environ.get('UR3_FT_GRIPPER_ROSDISTRO', '')
    missing = [n for n in ROSDISTRO_FILES if not os.path.isfile(os.path.join(rosdistro, n))]
    if not rosdistro or missing:
        return False, ('UR3_FT_GRIPPER_ROSDISTRO=%r lacks %s: point it at a folder with rosdistro\'s '
                       'base.yaml, python.yaml and noetic-distribution.yaml' % (rosdistro, ', '.join(missing)))
    rosdistro = os.path.abspath(rosdistro)
    with tempfile.TemporaryDirectory(prefix='rosdep_') as folder:
        env = rosdep_environment(rosdistro, folder)
        update = subprocess.run(['rosdep', 'update', '--rosdistro', 'noetic'], env=env, cwd=folder,
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
        if update.returncode != 0:
            return False, 'rosdep update from %s failed:\n%s' % (rosdistro, update.stdout)
        run = subprocess.run(['catkin_lint', '-W2', '--strict', '-q', package_dir], env=env, cwd=folder,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    # stderr: catkin_lint's notes (e.g. manifests it could not download); the verdict is stdout.
    if 'cannot load rosdep database' in run.stderr:
        return False, run.stderr.strip()
    report = run.stdout.strip()
    return run.returncode == 0 and not report, report


def main(package_dir, result_xml):
    passed, report = lint(package_dir)
    suite = ET.Element('testsuite', name='catkin_lint', tests='1', failures='0' if passed else '1')
    case = ET.SubElement(suite, 'testcase', classname='catkin_lint', name='catkin_lint_reports_nothing')
    if not passed:
        ET.SubElement(case, 'failure', message='catkin_lint reported problems').text = report
        print(report)
    ET.ElementTree(suite).write(result_xml)
    print('catkin_lint (with rosdep data): %s' % ('clean' if passed else 'problems found'))
    return 0 if passed else 1


if __name__ == '__main__':
    sys.exit(main(*sys.argv[1:]))
