"""The snippets of README.md and doc/*.md that load the model into MuJoCo or PyBullet run as pasted.

Each bash block with a `python3 -c` line runs whole, in order, in a fresh
folder, with this Python (the consumers venv's, which has MuJoCo and PyBullet)
first on PATH as `python3`; its rosrun lines run the package's own commands in
the sourced workspace. test/unit/test_doc_snippets.py runs the other snippets.
"""
import json
import os
import subprocess
import sys

import pytest

from conftest import PACKAGE_DIR

SNIPPETS = json.loads(subprocess.run(
    [sys.executable, os.path.join(PACKAGE_DIR, 'tools', 'doc_snippets.py'), '--json'], stdout=subprocess.PIPE,
    universal_newlines=True, check=True).stdout)
BLOCKS = [b for b in SNIPPETS if b['lang'] == 'bash' and any(c['text'].startswith('python3 -c') for c in b['commands'])]


def test_the_docs_have_such_blocks():
    assert BLOCKS, 'no bash block of the docs loads the model in Python: this test has nothing to run'


@pytest.mark.parametrize('block', BLOCKS, ids=['%s:%d' % (b['file'], b['line']) for b in BLOCKS])
def test_the_block_runs_as_pasted(block, tmp_path):
    env = dict(os.environ, PATH=os.path.dirname(sys.executable) + os.pathsep + os.environ['PATH'])
    run = subprocess.run(['bash', '-e', '-c', block['text']], cwd=str(tmp_path), env=env, stdin=subprocess.DEVNULL,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, timeout=600)
    assert run.returncode == 0, '%s:%d failed:\n%s\n%s' % (block['file'], block['line'], block['text'],
                                                          run.stderr[-3000:])
