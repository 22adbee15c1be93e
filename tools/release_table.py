#!/usr/bin/env python3
"""What tools/quickstart installs on each release: the tables in tools/releases/, read for bash.

A table is tools/releases/<name>.yaml. A key is looked up in the table, then in
the table it `extends`, then in common.yaml; the first that has it answers
(a table that names a key replaces the value below it, whole). The keys:

    name             what the release is called in messages
    quickstart       true: tools/quickstart sets the release up (else only its leg is tested)
    os_release       "<ID> <VERSION_ID>" of /etc/os-release that picks this table
    ros_setup        the setup.bash of a ROS the user installs first (none: on the system paths)
    ros_install      where the user is told to install that ROS from
    apt, ros_apt, release_apt   apt packages: everywhere, this ROS's, this release's
    programs, ros_programs      {program: package} checked on PATH after set-up
    python_modules   {module: package} checked with the workspace venv's python3
    venv, ros_venv   PyPI pins of the workspace venv: everywhere, where the ROS lacks them
    physics          PyPI pins of MuJoCo (physics:=true) for the release's Python
    consumers, consumers_apt    the consumers venv's PyPI pins, and the apt packages beside it
    consumers_absent {consumer: why}: test/consumers/test_<consumer>.py is not part of the
                     release's suite, for no registry has that consumer for it
    consumers_cxxflags  compiler flags (CFLAGS and CXXFLAGS) for the consumers pip builds from source
    message_packages, ros_message_packages   generated from upstream's definitions
    repos, ros_repos repos/<name>.repos to clone
    overlays         tools/<folder> of packages that fill the ROS's gaps (tools/debian)
    setup_seconds    {step: seconds} each set-up step takes, for the time left it announces
    cell_tests_variant  the robotiq variant whose pass of `quickstart test` runs the cell's targets
                     (test/variant_scope.yaml); the other variants' passes leave them out
    leg              {python, pins, build_pins, pip_options}: the release's Python leg

    release_table.py TABLE KEY       the value: a list one item a line, a mapping
                                     "key value" a line, a scalar as it is, nothing if unset
    release_table.py TABLE leg.pins  a key of a mapping
    release_table.py legs            "python table" a line, for the tables that have a leg

Exit status 0 (a known key that no table sets prints nothing), or 2 with one line on a table
or key that does not exist.
"""
import os
import sys

import yaml

FOLDER = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'releases')
KEYS = ('name', 'quickstart', 'os_release', 'ros_setup', 'ros_install', 'apt', 'ros_apt', 'release_apt', 'programs',
        'ros_programs', 'python_modules', 'venv', 'ros_venv', 'physics', 'consumers', 'consumers_apt', 'consumers_absent',
        'consumers_cxxflags', 'message_packages', 'ros_message_packages', 'repos', 'ros_repos', 'overlays',
        'setup_seconds', 'cell_tests_variant', 'leg', 'extends')


def load(name):
    path = os.path.join(FOLDER, name + '.yaml')
    if not os.path.isfile(path):
        raise LookupError('no table %s in %s' % (name, FOLDER))
    with open(path) as stream:
        table = yaml.safe_load(stream) or {}
    unknown = sorted(set(table) - set(KEYS))
    if unknown:
        raise LookupError('%s: unknown keys %s (known: %s)' % (path, ', '.join(unknown), ', '.join(KEYS)))
    return table


def chain(name):
    """The tables a lookup in `name` reads, in order."""
    tables = []
    while name and name != 'common':
        table = load(name)
        tables.append(table)
        name = table.get('extends')
    return tables + [load('common')]


def lookup(name, key):
    head, _, rest = key.partition('.')
    if head not in KEYS:
        raise LookupError('no key %s (known: %s)' % (head, ', '.join(KEYS)))
    for table in chain(name):
        if head in table:
            value = table[head]
            if rest:
                value = (value or {}).get(rest)
            return value
    return None


def lines(value):
    if value is None:
        return []
    if isinstance(value, list):
        return [str(item) for item in value]
    if isinstance(value, dict):
        return ['%s %s' % (key, item) for key, item in value.items()]
    return [str(value)]


def legs():
    found = []
    for file_name in sorted(os.listdir(FOLDER)):
        name, extension = os.path.splitext(file_name)
        if extension == '.yaml' and name != 'common':
            leg = load(name).get('leg')
            if leg:
                found.append((str(leg['python']), name))
    return ['%s %s' % pair for pair in sorted(found, key=lambda pair: tuple(map(int, pair[0].split('.'))))]


def main(argv):
    try:
        if argv == ['legs']:
            output = legs()
        elif len(argv) == 2:
            output = lines(lookup(*argv))
        else:
            print('usage: release_table.py TABLE KEY | legs', file=sys.stderr)
            return 2
    except LookupError as error:
        print('release_table: %s' % error, file=sys.stderr)
        return 2
    for line in output:
        print(line)
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
