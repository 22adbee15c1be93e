"""Command-line entry points; each prints one error line and exits non-zero on bad input."""

import argparse
import os
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


def _write(text, output):
    """`text` to the file `output`, or to stdout when no -o was given."""
    if output:
        with open(output, 'w') as f:
            f.write(text)
    else:
        sys.stdout.write(text)


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
        _write(description.to_xml(doc), args.output)
    except description.DescriptionError as e:
        print('expand_description: error: %s' % e, file=sys.stderr)
        return 1
    except ImportError as e:
        print('expand_description: error: %s is missing for %s: use the python3 that has the ROS '
              'modules (source your catkin workspace, or run bash tools/quickstart shell)' % (
                  e.name, sys.executable), file=sys.stderr)
        return 1
    except OSError as e:
        print('expand_description: error: %s' % e, file=sys.stderr)
        return 1
    return 0


class OneLineParser(argparse.ArgumentParser):
    """argparse, but a usage error is one line and exit status 1, like every other error here."""

    def error(self, message):
        print('%s: error: %s (see %s --help)' % (self.prog, message, self.prog), file=sys.stderr)
        sys.exit(1)


def _installed_ur_types():
    """': ur3, ur3e, ...' for --help; nothing when ur_description is missing (the run says so)."""
    try:
        return ': ' + ', '.join(description.ur_types())
    except description.DescriptionError:
        return ''


def _absolute_path(path):
    return os.path.abspath(path) if path else path


def _model_parser(prog, description_text):
    """The options every export command takes: which model, with which parameter files."""
    parser = OneLineParser(prog=prog, description=description_text)
    parser.add_argument('--ur-type', default='ur3',
                        help='UR model: a folder of the installed ur_description/config%s '
                             '(default: ur3)' % _installed_ur_types())
    parser.add_argument('--prefix', default='', help='prefix for every link and joint, e.g. left_')
    parser.add_argument('--no-ft-sensor', action='store_true',
                        help='leave out the FT 300; the gripper then sits on tool0 through the coupling')
    parser.add_argument('--no-gripper', action='store_true', help='leave out the 2F-140')
    parser.add_argument('--world', action='store_true', help='root the model at a world link')
    for arg, what in (('joint-limit-params', 'joint limits'),
                      ('kinematics-params', 'kinematic calibration (use your robot\'s own)'),
                      ('physical-params', 'physical parameters'), ('visual-params', 'meshes')):
        # A path on the command line is the shell's, relative to where the command runs; xacro
        # would take it relative to the top-level xacro file.
        parser.add_argument('--' + arg, default='', metavar='YAML', type=_absolute_path,
                            help="YAML file with the arm's %s (default: ur_description's file for "
                                 "--ur-type)" % what)
    return parser


def _model_mappings(args):
    from . import export
    return export.model_mappings(
        ur_type=args.ur_type, prefix=args.prefix, ft_sensor=not args.no_ft_sensor,
        gripper=not args.no_gripper, world=args.world,
        joint_limit_params=args.joint_limit_params, kinematics_params=args.kinematics_params,
        physical_params=args.physical_params, visual_params=args.visual_params)


def _run_export(prog, write):
    """`write()`, with every error as one line naming the fix in this command's syntax."""
    try:
        write()
    except description.DescriptionError as e:
        print('%s: error: %s' % (prog, e), file=sys.stderr)
        return 1
    except OSError as e:
        print('%s: error: %s' % (prog, e), file=sys.stderr)
        return 1
    return 0


def export_urdf_main(argv=None):
    from . import export
    parser = _model_parser(
        'export_urdf',
        'Write a flattened URDF of a UR arm + Robotiq FT 300 + 2F-140 (either part '
        'optional) for simulators and libraries that do not read xacro or ROS '
        'packages. Mesh paths stay package:// URIs unless --absolute-meshes is given. '
        'Errors are one line and exit with status 1; no file is written then.')
    parser.add_argument('--absolute-meshes', action='store_true',
                        help='write mesh paths as absolute file paths instead of package:// URIs')
    parser.add_argument('-o', '--output', help='write the URDF to this file instead of stdout')
    args = parser.parse_args(argv)
    mappings = _model_mappings(args)
    return _run_export('export_urdf', lambda: _write(
        export.export_urdf(mappings, absolute=args.absolute_meshes), args.output))


def export_mjcf_main(argv=None):
    from . import mjcf
    parser = _model_parser(
        'export_mjcf',
        'Write a MuJoCo model (MJCF) of a UR arm + Robotiq FT 300 + 2F-140 (either part '
        'optional): the mimic joints as equality constraints, the linkage pairs that always '
        'touch excluded from contact, collision meshes as STL files in <OUTPUT without '
        'extension>_meshes/, and a position actuator on finger_joint. Errors are one line '
        'and exit with status 1.')
    parser.add_argument('-o', '--output', required=True, metavar='FILE.xml',
                        help='write the MJCF here (required: the meshes go beside it)')
    args = parser.parse_args(argv)
    mappings = _model_mappings(args)
    return _run_export('export_mjcf', lambda: mjcf.export_mjcf(mappings, args.output))
