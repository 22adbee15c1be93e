#!/usr/bin/env python3
"""Keeps this package's xacro and YAML within what Noetic's xacro reads.

CI expands the model with PyPI's xacro 2.1.1 (no registry has Noetic's 1.14),
which reads more than the xacro 1.14 that users run. Each rule below names a
construct and the release that added it, from xacro's CHANGELOG (Noetic's
branch, 1.14.17); a construct that CHANGELOG does not list at all, but xacro 2
reads, is marked None: no 1.14 release has it. The floor is what package.xml
declares for xacro (version_gte), so one home holds the version users need.

    python3 tools/xacro_guard.py [FILE ...]   default: urdf/**/*.xacro, config/**/*.yaml, config/**/*.xacro
    python3 tools/xacro_guard.py --changelog CHANGELOG.rst   checks the rules against xacro's CHANGELOG

Prints one line per finding and exits 1 when there is any.
"""
import collections
import glob
import os
import re
import sys

from catkin_pkg.package import parse_package

PKG_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

Rule = collections.namedtuple('Rule', 'construct pattern kind version changelog')
# kind: 'xacro' (xacro files) or 'yaml' (files read by xacro.load_yaml).
RULES = (
    Rule('optional includes', r'<xacro:include\b[^>]*\boptional=', 'xacro', '1.14.1',
         'allow optional xacro includes'),
    Rule('!degrees / !radians YAML tags', r'!(degrees|radians)\b', 'yaml', '1.14.5',
         'yaml constructors ``!degrees`` and ``!radians``'),
    Rule('dotify()', r'\bdotify\s*\(', 'xacro', '1.14.7', 'Expose YamlDictWrapper as dotify()'),
    Rule('an expression after !degrees / !radians', r'!(degrees|radians)\s+[^\s#\d.+-]|!(degrees|radians)\s+[\d.]+\s*[*/+-]',
         'yaml', '1.14.9', 'Generalize yaml ``!degrees`` constructor: Enable expressions as well'),
    Rule('sorted() / set()', r'\$\{[^}]*\b(sorted|set)\s*\(', 'xacro', '1.14.9',
         'Allow more builtin symbols: sorted, set'),
    Rule('the xacro. namespace (xacro.load_yaml, xacro.print_location, ...)', r'\$\{[^}]*\bxacro\.', 'xacro', '1.14.10',
         'Expose xacro functions into ``xacro`` namespace'),
    Rule('tokenize()', r'\$\{[^}]*\btokenize\s*\(', 'xacro', '1.14.10', '``tokenize(string'),
    Rule('removing a property', r'<xacro:property\b[^>]*\bremove=', 'xacro', '1.14.10',
         'Allow removal of a property definition'),
    Rule('greedy property evaluation', r'<xacro:property\b[^>]*\blazy_eval=', 'xacro', '1.14.10',
         'Allow greedy property evaluation'),
    Rule('a property name from an expression', r'<xacro:property\b[^>]*\bname="\$\{', 'xacro', '1.14.10',
         'Allow property names to be evaluated from an expression'),
    Rule('xacro.arg()', r'\bxacro\.arg\s*\(', 'xacro', '1.14.11', 'Expose ``xacro.arg()``'),
    Rule('comment evaluation', r'<!--\s*xacro:eval-comments', 'xacro', '1.14.13',
         'Only optionally activate comment evaluation'),
    Rule('python.abs()', r'\bpython\.abs\s*\(|\$\{[^}]*(?<![\w.])abs\s*\(', 'xacro', '1.14.17', 'Expose python.abs()'),
    Rule('length units in YAML (!meters, !millimeters, !foot, !inches)', r'!(meters|millimeters|foot|inches)\b',
         'yaml', None, None),
)


def version_tuple(text):
    return tuple(int(part) for part in text.split('.'))


def declared_floor(package_xml=os.path.join(PKG_DIR, 'package.xml')):
    """The xacro version package.xml asks for (version_gte of its xacro dependency)."""
    package = parse_package(package_xml)
    for dependency in package.exec_depends + package.build_depends:
        if dependency.name == 'xacro' and dependency.version_gte:
            return dependency.version_gte
    raise ValueError('%s declares no version_gte for xacro' % package_xml)


def kind_of(path):
    return 'yaml' if path.endswith(('.yaml', '.yml')) else 'xacro'


def findings(paths, floor):
    """(path, line number, rule) for every construct newer than `floor`."""
    newer = [r for r in RULES if r.version is None or version_tuple(r.version) > version_tuple(floor)]
    for path in paths:
        with open(path) as f:
            lines = f.read().splitlines()
        for number, line in enumerate(lines, 1):
            for rule in newer:
                if rule.kind == kind_of(path) and re.search(rule.pattern, line):
                    yield path, number, rule


def describe(path, number, rule, floor):
    needs = ('xacro >= %s' % rule.version) if rule.version else 'xacro 2 (no 1.14 release has it)'
    return ('%s:%d: %s needs %s, but package.xml declares xacro >= %s: use what %s reads, '
            'or raise version_gte' % (os.path.relpath(path), number, rule.construct, needs, floor, floor))


def package_files():
    patterns = ('urdf/**/*.xacro', 'config/**/*.yaml', 'config/**/*.xacro')
    return sorted(p for pattern in patterns for p in glob.glob(os.path.join(PKG_DIR, pattern), recursive=True))


def changelog_sections(path):
    """{version: text of that release's entries} from xacro's CHANGELOG.rst."""
    with open(path) as f:
        text = f.read()
    parts = re.split(r'^(\d+\.\d+\.\d+) \(\d{4}-\d{2}-\d{2}\)\n-+\n', text, flags=re.M)
    return dict(zip(parts[1::2], parts[2::2]))


def changelog_mismatches(path):
    """Rules whose release does not list their construct, and constructs marked None that a release lists."""
    sections = changelog_sections(path)
    for rule in RULES:
        if rule.version is not None and rule.changelog not in sections.get(rule.version, ''):
            yield '%s: %s does not list %r under %s' % (path, os.path.basename(path), rule.changelog, rule.version)
        if rule.version is None:
            for word in re.findall(r'!(\w+)', rule.construct):
                listed = [v for v, entries in sections.items() if '!' + word in entries]
                if listed:
                    yield '%s: %s lists !%s under %s' % (path, os.path.basename(path), word, ', '.join(listed))


def main(argv):
    if argv[:1] == ['--changelog']:
        if len(argv) != 2 or not os.path.isfile(argv[1]):
            print('xacro_guard: --changelog needs the path of xacro\'s CHANGELOG.rst')
            return 2
        lines = list(changelog_mismatches(argv[1]))
        for line in lines:
            print('xacro_guard: ' + line)
        return 1 if lines else 0
    floor = declared_floor()
    lines = [describe(path, number, rule, floor) for path, number, rule in findings(argv or package_files(), floor)]
    for line in lines:
        print('xacro_guard: ' + line)
    return 1 if lines else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
