#!/usr/bin/env python3
"""The snippets of README.md and doc/*.md: fenced code blocks with a language tag.

The tests run what a user would paste (test/unit/test_doc_snippets.py,
test/consumers/test_doc_snippets.py) from the Markdown files themselves, so
a page's edit is tested. A block's language tag says what it is: `bash`
(commands, one per line, a trailing backslash continuing it), `xml` (a xacro
or launch fragment), `python`, or `text` (output, diagrams: not run).

    python3 tools/doc_snippets.py          # list every snippet and command
    python3 tools/doc_snippets.py --json   # the same for the tests
"""
import argparse
import glob
import json
import os
import sys

PKG_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FENCE = '```'


def markdown_files(pkg_dir=PKG_DIR):
    return [os.path.join(pkg_dir, 'README.md')] + sorted(glob.glob(os.path.join(pkg_dir, 'doc', '*.md')))


def blocks(path, pkg_dir=PKG_DIR):
    """Each fenced block of `path` as {file, line (of its first line of code), lang, text}."""
    found, current = [], None
    with open(path) as f:
        for number, line in enumerate(f, 1):
            stripped = line.strip()
            if current is None and stripped.startswith(FENCE):
                lang = stripped[len(FENCE):].strip()
                if not lang:
                    raise ValueError('%s:%d: a fenced block without a language tag: say what it is '
                                     '(bash, xml, python, text)' % (os.path.relpath(path, pkg_dir), number))
                current = {'file': os.path.relpath(path, pkg_dir), 'line': number + 1, 'lang': lang, 'lines': []}
            elif current is not None and stripped == FENCE:
                current['text'] = ''.join(current.pop('lines'))
                found.append(current)
                current = None
            elif current is not None:
                current['lines'].append(line)
    if current is not None:
        raise ValueError('%s:%d: a fenced block is not closed' % (os.path.relpath(path, pkg_dir), current['line'] - 1))
    return found


def commands(block):
    """The commands of a bash block as {line, text}: backslash continuations joined,
    blank and comment-only lines left out."""
    found, parts, start = [], [], None
    for offset, line in enumerate(block['text'].splitlines()):
        if not parts and (not line.strip() or line.lstrip().startswith('#')):
            continue
        if not parts:
            start = block['line'] + offset
        if line.rstrip().endswith('\\'):
            parts.append(line.rstrip()[:-1].strip())
            continue
        parts.append(line.strip())
        found.append({'line': start, 'text': ' '.join(parts)})
        parts = []
    return found


def snippets(pkg_dir=PKG_DIR):
    found = []
    for path in markdown_files(pkg_dir):
        for block in blocks(path, pkg_dir):
            if block['lang'] == 'bash':
                block['commands'] = commands(block)
            found.append(block)
    return found


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--json', action='store_true', help='print the snippets as JSON')
    args = parser.parse_args(argv)
    try:
        found = snippets()
    except ValueError as exc:
        print('doc_snippets: error: %s' % exc, file=sys.stderr)
        return 1
    if args.json:
        json.dump(found, sys.stdout, indent=1)
        print()
        return 0
    for block in found:
        print('%s:%d %s' % (block['file'], block['line'], block['lang']))
        for command in block.get('commands', []):
            print('    %s' % command['text'])
    return 0


if __name__ == '__main__':
    sys.exit(main())
