#!/usr/bin/env python3
"""Sum up the JUnit files of a test run: list what failed, end with 'N passed, N failed'.

Skipped tests count as failures here: a test that did not run proved nothing.
tools/run_tests.py counts with the same functions while the tests run.
Usage: test_summary.py RESULTS_DIR
"""
import os
import sys
import xml.etree.ElementTree as ET


def cases(path):
    root = ET.parse(path).getroot()
    suites = [root] if root.tag == 'testsuite' else root.iter('testsuite')
    for suite in suites:
        for case in suite.findall('testcase'):
            yield case


class Tally(object):
    """Passed count, failed and skipped labels ('<file>: <test>'), added file by file."""

    def __init__(self):
        self.passed, self.failed, self.skipped = 0, [], []

    def add_file(self, path, where):
        """Count the result file `path`, labelled `where`; returns the labels of its failures."""
        try:
            found = list(cases(path))
        except ET.ParseError as e:
            label = '%s: unreadable result file (%s)' % (where, e)
            self.failed.append(label)
            return [label]
        failed = []
        for case in found:
            label = '%s: %s' % (where, case.get('name'))
            if case.find('failure') is not None or case.find('error') is not None:
                failed.append(label)
            elif case.find('skipped') is not None:
                self.skipped.append(label)
            else:
                self.passed += 1
        self.failed += failed
        return failed

    def line(self):
        """The closing line CI reads: 'tests: N passed, N failed[, N skipped]'."""
        line = 'tests: %d passed, %d failed' % (self.passed, len(self.failed))
        if self.skipped:
            line += ', %d skipped' % len(self.skipped)
        return line


def result_files(results_dir):
    """Every .xml below results_dir, in a stable order, with its path relative to results_dir."""
    for folder, _, files in sorted(os.walk(results_dir)):
        for name in sorted(f for f in files if f.endswith('.xml')):
            path = os.path.join(folder, name)
            yield path, os.path.relpath(path, results_dir)


def tally(results_dir):
    counted = Tally()
    for path, where in result_files(results_dir):
        counted.add_file(path, where)
    return counted


def main(results_dir):
    counted = tally(results_dir)
    for label in counted.failed:
        print('FAILED  ' + label)
    for label in counted.skipped:
        print('SKIPPED ' + label)
    print(counted.line())
    return 0 if counted.passed and not counted.failed and not counted.skipped else 1


if __name__ == '__main__':
    sys.exit(main(sys.argv[1]))
