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


def failure_reason(case, width=300):
    """The one line that says why `case` failed.

    pytest puts it in the message attribute; rosunit leaves that out and puts
    the assertion first, before the traceback; a bare traceback ends with it.
    """
    found = case.find('failure')
    if found is None:
        found = case.find('error')
    if found is None:
        return ''
    lines = [line.strip() for line in (found.text or '').splitlines() if line.strip()]
    reason = (found.get('message') or '').strip()
    if not reason and lines:
        reason = lines[-1] if lines[0].startswith('Traceback') else lines[0]
    reason = ' '.join((reason or found.get('type') or '').split())
    return reason if len(reason) <= width else reason[:width - 3] + '...'


class Tally(object):
    """Passed count, failed and skipped labels ('<file>: <test>'), added file by file.

    `reasons` maps a failed label to the line saying why, so a CI log that keeps
    nothing else still shows what went wrong.
    """

    def __init__(self):
        self.passed, self.failed, self.skipped = 0, [], []
        self.reasons = {}

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
                self.reasons[label] = failure_reason(case)
            elif case.find('skipped') is not None:
                self.skipped.append(label)
            else:
                self.passed += 1
        self.failed += failed
        return failed

    def failed_line(self, label):
        """'FAILED  <label>', and on the next line why, when the result says."""
        reason = self.reasons.get(label)
        return 'FAILED  %s\n        %s' % (label, reason) if reason else 'FAILED  ' + label

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
        print(counted.failed_line(label))
    for label in counted.skipped:
        print('SKIPPED ' + label)
    print(counted.line())
    return 0 if counted.passed and not counted.failed and not counted.skipped else 1


if __name__ == '__main__':
    sys.exit(main(sys.argv[1]))
