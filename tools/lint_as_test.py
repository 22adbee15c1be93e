#!/usr/bin/env python3
"""Run catkin_lint on the package and record it as one JUnit test case.

Usage: lint_as_test.py PACKAGE_DIR RESULT_XML
"""
import subprocess
import sys
import xml.etree.ElementTree as ET


def main(package_dir, result_xml):
    run = subprocess.run(['catkin_lint', '-W2', '--strict', package_dir],
                         stdout=subprocess.PIPE, universal_newlines=True)
    report = run.stdout.strip()
    suite = ET.Element('testsuite', name='catkin_lint', tests='1',
                       failures='0' if run.returncode == 0 and not report else '1')
    case = ET.SubElement(suite, 'testcase', classname='catkin_lint', name='catkin_lint_reports_nothing')
    if run.returncode != 0 or report:
        ET.SubElement(case, 'failure', message='catkin_lint reported problems').text = report
        print(report)
    ET.ElementTree(suite).write(result_xml)
    print('catkin_lint: %s' % ('clean' if suite.get('failures') == '0' else 'problems found'))


if __name__ == '__main__':
    main(*sys.argv[1:])
