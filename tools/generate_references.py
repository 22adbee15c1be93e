#!/usr/bin/env python3
"""Write the generated references in doc/ from where their facts are declared.

- doc/launch_reference.md, from the launch files: each file's header comment
  gives its summary and example commands, each <arg>'s doc= its meaning.
- doc/node_parameters.md, from the nodes' declaration tables named in
  NODE_PARAMETER_TABLES (each a sequence of entries with name, default and
  doc: devices/sim_params.py's Param), with the first line of the declaring
  module's docstring.
The sources stay the one home of those facts; the pages are never edited.

    python3 tools/generate_references.py           # rewrite the pages
    python3 tools/generate_references.py --check   # exit 1 if one is stale (the unit tests run this)
"""
import argparse
import difflib
import glob
import importlib
import os
import sys
import textwrap

from lxml import etree

PKG_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COMMAND = 'python3 tools/generate_references.py'
LAUNCH_PAGE = 'launch_reference.md'
NODE_PAGE = 'node_parameters.md'
# Node (as launched) -> 'module:ATTRIBUTE' of its parameter declaration table.
# Each entry: .name ('~rate'), .default, .doc (or a dict of those); a default
# with .shown (worked out when the node starts) renders as that text.
NODE_PARAMETER_TABLES = {
    'robotiq_ft_sensor': 'ur3_ft_gripper_description.devices.ft300_sim:PARAMETERS',
    'robotiq2FGripper': 'ur3_ft_gripper_description.devices.gripper_sim:PARAMETERS',
    'gripper_joint_states': 'ur3_ft_gripper_description.devices.gripper_joint_states:PARAMETERS',
    'ur_hardware_interface': 'ur3_ft_gripper_description.devices.ur_arm.settings:PARAMETERS',
    'ur_controller_sim': 'ur3_ft_gripper_description.devices.ur_arm.controller_sim:PARAMETERS',
}


class LaunchFileError(ValueError):
    """A launch file the reference cannot describe (unreadable, or an argument without doc=)."""


def parse(path):
    """(root element, text of the comment before it, dedented; '' if none)."""
    try:
        root = etree.parse(path).getroot()
    except etree.XMLSyntaxError as exc:
        raise LaunchFileError('%s: not well-formed XML (%s)' % (os.path.relpath(path, PKG_DIR), exc))
    comments = [node.text for node in root.itersiblings(preceding=True) if node.tag is etree.Comment]
    return root, textwrap.dedent(comments[-1]).strip('\n') if comments else ''


def comment_parts(comment):
    """A header comment as ('text', paragraph) and ('bash', commands) parts, in order.

    Indented lines are example commands (a blank line between two of them
    keeps one block); the rest is prose, in paragraphs split at blank lines.
    """
    parts, lines, kind = [], [], None

    def flush():
        if lines:
            parts.append(('text', ' '.join(l.strip() for l in lines)) if kind == 'text'
                         else ('bash', textwrap.dedent('\n'.join(lines))))
            del lines[:]

    for line in comment.splitlines():
        if not line.strip():
            if kind == 'text':
                flush()
            continue
        this = 'bash' if line[:1].isspace() else 'text'
        if this != kind:
            flush()
            kind = this
        lines.append(line)
    flush()
    return parts


def prose(text):
    """Markdown for plain text: what would read as HTML or a table border, escaped."""
    return text.replace('&', '&amp;').replace('<', '&lt;').replace('>', '&gt;').replace('|', '\\|')


def code(text):
    return '`%s`' % text if text else '`""`'


def arguments(root, path):
    """The file's own <arg>s (not those passed to an <include>): settable ones as
    (name, default or None, doc), constants as (name, value)."""
    settable, constants = [], []
    for arg in root.findall('arg'):
        name = arg.get('name')
        if 'value' in arg.attrib:
            if '$(' not in arg.get('value'):
                constants.append((name, arg.get('value')))
            continue
        doc = arg.get('doc')
        if not doc:
            raise LaunchFileError('%s: arg %r has no doc=: say what it does (STYLE: doc= on every launch arg)'
                                  % (os.path.relpath(path, PKG_DIR), name))
        settable.append((name, arg.get('default'), ' '.join(doc.split())))
    return settable, constants


def launch_files(launch_dir):
    found = glob.glob(os.path.join(launch_dir, '*.launch')) + glob.glob(os.path.join(launch_dir, '*', '*.launch'))
    return sorted(found, key=lambda p: (os.path.dirname(p) != launch_dir, os.path.relpath(p, launch_dir)))


def section(path, launch_dir):
    root, comment = parse(path)
    settable, constants = arguments(root, path)
    name = os.path.relpath(path, launch_dir)
    lines = ['## %s' % name, '']
    for kind, text in comment_parts(comment):
        if kind == 'text':
            lines += textwrap.wrap(prose(text), 100, break_on_hyphens=False, break_long_words=False) + ['']
        else:
            lines += ['```bash', text, '```', '']
    if settable:
        lines += ['| argument | default | meaning |', '| --- | --- | --- |']
        for arg, default, doc in settable:
            shown = '**required**' if default is None else code(default.replace('|', '\\|'))
            lines.append('| `%s` | %s | %s |' % (arg, shown, prose(doc)))
        lines.append('')
    else:
        lines += ['No arguments.', '']
    if constants:
        lines += ['Set by this file: %s.' % ', '.join('`%s` = `%s`' % c for c in constants), '']
    return lines


def render_launch_page(launch_dir=None):
    launch_dir = launch_dir or os.path.join(PKG_DIR, 'launch')
    files = launch_files(launch_dir)
    lines = [
        '# Launch files and their arguments',
        '',
        '<!-- Generated by `%s` from the launch files: edit them, not this file. -->' % COMMAND,
        '',
        'Generated from each launch file\'s header comment and the `doc=` of its arguments. An argument',
        'without a default is **required**. `roslaunch --ros-args ur3_ft_gripper_description FILE` lists',
        'the same arguments on your machine.',
        '',
    ]
    lines += ['- [%s](#%s)' % (os.path.relpath(p, launch_dir), anchor(os.path.relpath(p, launch_dir)))
              for p in files] + ['']
    for path in files:
        lines += section(path, launch_dir)
    return '\n'.join(lines).rstrip('\n') + '\n'


def anchor(title):
    """GitHub's anchor for a heading: lower case, punctuation but '-' and '_' dropped, spaces as '-'."""
    kept = ''.join(c for c in title.lower() if c.isalnum() or c in ' -_')
    return kept.replace(' ', '-')


def entry_field(entry, field):
    return entry[field] if isinstance(entry, dict) else getattr(entry, field)


def load_table(where):
    """(the table 'module:ATTRIBUTE' names, the first line of the module's docstring or '')."""
    module, _, attribute = where.partition(':')
    try:
        found = importlib.import_module(module)
        table = getattr(found, attribute)
    except (ImportError, AttributeError) as exc:
        raise LaunchFileError('node parameter table %s: %s' % (where, exc))
    return table, (found.__doc__ or '').strip().split('\n')[0]


def shown_default(default):
    if default is None:
        return '(unset)'
    if hasattr(default, 'shown'):
        return prose(default.shown)
    if isinstance(default, bool):
        return code(str(default).lower())  # as a launch file writes it
    return code(str(default).replace('|', '\\|'))


def render_node_page(tables, declared_in):
    """doc/node_parameters.md from {node: (table, summary)} and {node: 'module:ATTRIBUTE'}."""
    lines = [
        '# Node parameters',
        '',
        '<!-- Generated by `%s` from the nodes\' parameter declarations: edit them, not this file. -->' % COMMAND,
        '',
        'The private parameters of the package\'s nodes, under the names the launch files give the nodes;',
        'the launch files set most of them from their arguments ([launch_reference.md](%s)). A node' % LAUNCH_PAGE,
        'stops with one line naming a parameter it cannot use.',
        '',
    ]
    lines += ['- [%s](#%s)' % (node, anchor(node)) for node in sorted(tables)] + ['']
    for node in sorted(tables):
        table, summary = tables[node]
        module, _, attribute = declared_in[node].partition(':')
        lines += ['## %s' % node, '']
        if summary:
            lines += textwrap.wrap(prose(summary), 100, break_on_hyphens=False, break_long_words=False) + ['']
        if not table:
            lines += ['No ROS parameters (`%s` in `%s` is empty): it takes its command line.' % (attribute, module), '']
            continue
        lines += ['Declared in `%s` (`%s`).' % (module, attribute), '',
                  '| parameter | default | meaning |', '| --- | --- | --- |']
        for entry in table:
            lines.append('| `%s` | %s | %s |' % (entry_field(entry, 'name'),
                                                shown_default(entry_field(entry, 'default')),
                                                prose(' '.join(str(entry_field(entry, 'doc')).split()))))
        lines.append('')
    return '\n'.join(lines).rstrip('\n') + '\n'


def pages(launch_dir=None, node_tables=None):
    """{file name in doc/: text} of every generated page."""
    tables = NODE_PARAMETER_TABLES if node_tables is None else node_tables
    found = {LAUNCH_PAGE: render_launch_page(launch_dir)}
    if tables:
        found[NODE_PAGE] = render_node_page({node: load_table(where) for node, where in tables.items()}, tables)
    return found


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--check', action='store_true', help='exit 1 if a page differs from what would be written')
    parser.add_argument('--doc-dir', default=os.path.join(PKG_DIR, 'doc'), help='where the pages go (default: doc/)')
    parser.add_argument('--launch-dir', default=None, help=argparse.SUPPRESS)
    parser.add_argument('--node-table', action='append', metavar='NODE=MODULE:ATTRIBUTE', help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    tables = dict(t.split('=', 1) for t in args.node_table) if args.node_table else None
    try:
        generated = pages(args.launch_dir, tables)
    except LaunchFileError as exc:
        print('generate_references: error: %s' % exc, file=sys.stderr)
        return 1
    if args.check:
        stale = []
        for name, text in sorted(generated.items()):
            path = os.path.join(args.doc_dir, name)
            current = open(path).read() if os.path.isfile(path) else ''
            if current != text:
                diff = difflib.unified_diff(current.splitlines(), text.splitlines(), 'written', 'generated',
                                            lineterm='', n=1)
                print('\n'.join(list(diff)[:40]), file=sys.stderr)
                stale.append(name)
        if stale:
            print('generate_references: %s stale: run `%s`' % (
                ', '.join('doc/' + name for name in stale) + (' is' if len(stale) == 1 else ' are'), COMMAND),
                file=sys.stderr)
            return 1
        return 0
    for name, text in generated.items():
        with open(os.path.join(args.doc_dir, name), 'w') as f:
            f.write(text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
