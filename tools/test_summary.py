#!/usr/bin/env python3
"""Sum up the JUnit files of a test run: list what failed, end with 'N passed, N failed'.

Skipped tests count as failures here: a test that did not run proved nothing.
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


def main(results_dir):
    passed, failed, skipped = 0, [], []
    for folder, _, files in sorted(os.walk(results_dir)):
        for name in sorted(f for f in files if f.endswith('.xml')):
            path = os.path.join(folder, name)
            where = os.path.relpath(path, results_dir)
            try:
                found = list(cases(path))
            except ET.ParseError as e:
                failed.append('%s: unreadable result file (%s)' % (where, e))
                continue
            for case in found:
                label = '%s: %s' % (where, case.get('name'))
                if case.find('failure') is not None or case.find('error') is not None:
                    failed.append(label)
                elif case.find('skipped') is not None:
                    skipped.append(label)
                else:
                    passed += 1
    for label in failed:
        print('FAILED  ' + label)
    for label in skipped:
        print('SKIPPED ' + label)
    line = 'tests: %d passed, %d failed' % (passed, len(failed))
    if skipped:
        line += ', %d skipped' % len(skipped)
    print(line)
    return 0 if passed and not failed and not skipped else 1


if __name__ == '__main__':
    sys.exit(main(sys.argv[1]))
