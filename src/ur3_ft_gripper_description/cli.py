"""Command-line entry points; each prints one error line and exits non-zero on bad input."""

import argparse
import sys

from . import description

XACRO_ARG_HELP = 'xacro arguments, e.g. kinematics_params:=/path/to/my_robot_calibration.yaml'


def _split_mappings(parser, words):
    mappings = {}
    for word in words:
        name, sep, value = word.partition(':=')
        if not sep or not name:
            parser.error("'%s' is not a xacro argument; write name:=value" % word)
        mappings[name] = value
    return mappings


def expand_description_main(argv=None):
    parser = argparse.ArgumentParser(
        prog='expand_description',
        description='Drop-in for the xacro command: expands a xacro file (by default this '
                    "package's UR3 + FT 300 + 2F-140 model) into URDF, removes the extra "
                    'base_link that the jr-robotics 2F-140 macro adds, and checks that the '
                    'result is one tree. Errors are one line and exit with status 1.')
    parser.add_argument('input', nargs='?', help='xacro file (default: urdf/ur3_ft_gripper.xacro)')
    parser.add_argument('mappings', nargs='*', metavar='name:=value', help=XACRO_ARG_HELP)
    parser.add_argument('-o', '--output', help='write the URDF here instead of to stdout')
    args = parser.parse_args(argv)
    if args.input and ':=' in args.input:  # only mappings were given
        args.mappings.insert(0, args.input)
        args.input = None
    mappings = _split_mappings(parser, args.mappings)
    try:
        if args.input:
            doc = description.expand(args.input, mappings)
        else:
            doc = description.expand_model(mappings)
        text = description.to_xml(doc)
        if args.output:
            with open(args.output, 'w') as f:
                f.write(text)
        else:
            sys.stdout.write(text)
    except description.DescriptionError as e:
        print('expand_description: error: %s' % e, file=sys.stderr)
        return 1
    except ImportError as e:
        print('expand_description: error: %s is missing for %s: use the python3 that has the ROS '
              'modules (source your catkin workspace, or see README "Set-up")' % (
                  e.name, sys.executable), file=sys.stderr)
        return 1
    except OSError as e:
        print('expand_description: error: %s' % e, file=sys.stderr)
        return 1
    return 0
