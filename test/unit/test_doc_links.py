"""Every relative link of README.md and doc/*.md reaches a file of the repository, and its #anchor a heading."""
import glob
import os
import re

import pytest

from ur3_ft_gripper_testing.model import PACKAGE_DIR

PAGES = [os.path.join(PACKAGE_DIR, 'README.md')] + sorted(glob.glob(os.path.join(PACKAGE_DIR, 'doc', '*.md')))
LINK = re.compile(r'\]\(([^)\s]+)\)')


def anchors(path):
    """GitHub's anchors of a Markdown file's headings: lower case, punctuation but '-' and '_' dropped."""
    found = set()
    in_code = False
    with open(path) as f:
        for line in f:
            if line.strip().startswith('```'):
                in_code = not in_code
            elif not in_code and line.startswith('#'):
                title = line.lstrip('#').strip().lower()
                found.add(''.join(c for c in title if c.isalnum() or c in ' -_').replace(' ', '-'))
    return found


def links(path):
    with open(path) as f:
        text = re.sub(r'```.*?```', '', f.read(), flags=re.DOTALL)
    return [link for link in LINK.findall(text) if not re.match(r'[a-z]+://', link)]


@pytest.mark.parametrize('page', PAGES, ids=[os.path.relpath(p, PACKAGE_DIR) for p in PAGES])
def test_every_relative_link_resolves(page):
    broken = []
    for link in links(page):
        target, _, anchor = link.partition('#')
        path = os.path.normpath(os.path.join(os.path.dirname(page), target)) if target else page
        if not os.path.exists(path):
            broken.append('%s: no such file' % link)
        elif anchor and path.endswith('.md') and anchor not in anchors(path):
            broken.append('%s: no heading with that anchor' % link)
    assert not broken, '%s: %s' % (os.path.relpath(page, PACKAGE_DIR), '; '.join(broken))
