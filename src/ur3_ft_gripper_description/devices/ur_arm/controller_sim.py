"""The simulated UR controller alone, without ROS: its network interfaces on the robot's address, as URSim.

    ur_controller_sim --ur-type ur5e [--robot-ip 127.0.0.1] [--kinematics-params my_robot_calibration.yaml]

For code that talks to the robot itself rather than to ROS: ur_robot_driver
(started with robot_ip:=127.0.0.1, as against URSim), ur_rtde, dashboard
clients. The controller's core (core.ArmCore, kinematic joints) runs on the
wall clock at the generation's control rate, with the Dashboard Server,
the primary, secondary and real-time interfaces and RTDE (network_faces.py)
over it; no ROS node, topic or parameter. The model (its joint limits and
kinematics, which the primary interface reports and the driver checks its
calibration against) is the package's, expanded for the given UR type.
Bad input (an unknown model, an address the machine does not have, a port
taken) ends it with one line naming the problem and the fix.
"""

import argparse
import ipaddress
import os
import signal
import sys
import threading
import time

from ..network import external_control_urcap, listen

PERIOD = {'CB3': 0.008, 'e-Series': 0.002}
# No ROS parameters: the controller takes its command line (--ur-type, --robot-ip, --kinematics-params),
# as a program that is not a ROS node.
PARAMETERS = ()
# Behind the wall clock by more than this many periods (a stalled machine), the controller skips ahead
# rather than racing to catch up, as a real-time controller cannot catch up either.
MOST_BEHIND = 10


class ControllerError(RuntimeError):
    """A controller that cannot start: one line naming the problem and the fix."""


def build(ur_type, robot_ip, kinematics_params='', log=None, ports=None, script_socket_hosts='',
          external_control=None):
    """(core, faces, lock) of `ur_type`, its faces listening on `robot_ip` (not yet serving); `ports`:
    {face: port} for those not on the robot's own (network_faces.PORTS; 0: a free one); `script_socket_hosts`:
    where programs' sockets may reach beyond loopback (settings.socket_hosts); `external_control`: (host,
    port) of the driver's script sender, which the External Control URCap asks for the program when
    external_control.urp plays (None: the simulation stands in for the driver's program)."""
    from ...model import description, export
    from ...model.names import DescriptionError, shared_rospack
    from .. import sim_params
    from . import core as arm_core
    from . import joints, software
    from .network_faces import NetworkFaces
    from .settings import read_settings

    try:
        software.for_model(ur_type)
        urdf = description.to_xml(description.expand_model(export.model_mappings(
            ur_type=ur_type, kinematics_params=kinematics_params)))
        config = os.path.join(shared_rospack().get_path('ur_robot_driver'), 'config',
                              '%s_controllers.yaml' % ur_type)
        values = {'~ur_type': ur_type, '~controller_config_file': config, 'robot_description': urdf,
                  '~controllers': 'joint_state_controller scaled_pos_joint_traj_controller',
                  '~script_socket_hosts': script_socket_hosts,
                  # As a controller without its driver: powered, External Control loaded and not playing, so
                  # that a client's first program (ur_rtde's, the driver's headless one) is sent straight in.
                  '~program_running': False}
        settings = read_settings(lambda name, default=None: values.get(name, default))
    except (software.UnknownModel, DescriptionError, sim_params.ParamError) as error:
        raise ControllerError(str(error)) from None
    core = arm_core.ArmCore(settings, joints.KinematicJoints.from_settings(settings))
    lock = threading.RLock()

    def call(method, *args):
        with lock:
            return method(*args)

    try:
        faces = NetworkFaces(listen.checked_address(robot_ip), core, call, log or say, ports, external_control)
    except listen.ListenError as error:
        raise ControllerError(str(error)) from None
    return core, faces, lock


def say(text):
    print('ur_controller_sim: %s' % text, file=sys.stderr, flush=True)


def run(core, faces, lock, stop):
    """Step the controller every period of the wall clock until `stop` (a threading.Event) is set."""
    period = PERIOD[core.software.generation]
    deadline = time.monotonic()
    while not stop.is_set():
        with lock:
            snapshot = core.step(period)
            faces.after_cycle(period, snapshot)
            for level, text in core.take_messages():
                say('%s: %s' % (level, text))
        deadline += period
        late = time.monotonic() - deadline
        if late > MOST_BEHIND * period:
            deadline = time.monotonic()
        elif late < 0:
            stop.wait(-late)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--ur-type', default='ur5e', help='UR model (ur3, ur5e, ...): its software version, '
                                                         'generation and kinematics (default: ur5e)')
    parser.add_argument('--robot-ip', default=listen.LOOPBACK,
                        help='the address the interfaces listen on, as a robot\'s IP (default: %s, this machine '
                             'only; 127.0.0.2 for a second controller)' % listen.LOOPBACK)
    parser.add_argument('--kinematics-params', default='',
                        help='a calibration YAML (ur_calibration\'s output) instead of ur_description\'s default')
    parser.add_argument('--script-socket-hosts', default='',
                        help='addresses beyond loopback that URScript\'s socket_open, rpc_factory and modbus_* '
                             'functions may connect to: IPv4 addresses or networks (192.168.56.1, 192.168.56.0/24) '
                             'separated by commas (default: loopback only)')
    parser.add_argument('--external-control-host-ip', default=listen.LOOPBACK,
                        help='the External Control URCap\'s Host IP: where the driver\'s script sender runs, which '
                             'it asks for the program when external_control.urp plays (default: %s)'
                             % listen.LOOPBACK)
    parser.add_argument('--external-control-port', type=int, default=external_control_urcap.DEFAULT_PORT,
                        help='the URCap\'s Custom port: the script sender\'s (default: %d, the driver\'s '
                             'script_sender_port)' % external_control_urcap.DEFAULT_PORT)
    # roslaunch appends its own name:=value arguments (__name, __log) to any program it starts.
    args = parser.parse_args([a for a in (sys.argv[1:] if argv is None else argv) if ':=' not in a])
    if args.kinematics_params and not os.path.isfile(args.kinematics_params):
        say('--kinematics-params: there is no file %s: give your robot\'s calibration YAML (ur_calibration\'s '
            'output), or leave it out for ur_description\'s default' % args.kinematics_params)
        return 1
    try:
        ipaddress.IPv4Address(args.external_control_host_ip)
    except ValueError:
        say('--external-control-host-ip: %s is not an IPv4 address: give the address of the machine that runs '
            'ur_robot_driver (its script sender), e.g. 127.0.0.1' % args.external_control_host_ip)
        return 1
    if not 0 < args.external_control_port < 65536:
        say('--external-control-port: %d is not a TCP port: give the driver\'s script_sender_port (50002 by '
            'default)' % args.external_control_port)
        return 1
    try:
        core, faces, lock = build(args.ur_type, args.robot_ip, args.kinematics_params,
                                  script_socket_hosts=args.script_socket_hosts,
                                  external_control=(args.external_control_host_ip, args.external_control_port))
    except ControllerError as error:
        say(str(error))
        return 1
    stop = threading.Event()
    try:
        # Its script ends it quietly on Ctrl-C while it starts. From here, before it says where the faces
        # listen, Ctrl-C closes them and it exits 0: whoever saw them announced and interrupts it (a
        # supervisor, a test) gets that, whenever the interrupt comes.
        signal.signal(signal.SIGINT, signal.default_int_handler)
        faces.start()
        for server in faces.servers:
            say('%s on %s:%d' % (server.name, *server.server_address[:2]))
        if not listen.is_loopback(args.robot_ip):
            say('the interfaces listen on %s, beyond this machine' % args.robot_ip)
        run(core, faces, lock, stop)
    except KeyboardInterrupt:
        pass
    finally:
        faces.shutdown()
    return 0
