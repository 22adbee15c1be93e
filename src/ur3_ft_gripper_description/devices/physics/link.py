"""The private link between the physics cell and the FT 300 and 2F-140 nodes (no ROS).

The cell lives in the arm's process (node ``ur_hardware_interface``), which
steps it at the controller's rate; the simulated FT 300 (robotiq_ft_sensor)
and 2F-140 (robotiq2FGripper) keep their own processes and node names, and
reach the cell through a local socket, never through a ROS topic of this
package's invention. The socket is the standard library's
``multiprocessing.connection`` over AF_UNIX, in a folder only its user can
enter (its messages are pickles: the folder's permissions keep other users
out), with an optional shared key (HMAC challenge, ``authkey``).

Where the socket is (``cell_address``): a file in ``$ROS_HOME/ur3_ft_gripper_cell/``
(``~/.ros`` by default) named by a hash of the ROS master (its port and its
process id, which its API gives every node: a URI can name one master in
several ways, e.g. localhost or the host name) and the resolved name of the
arm's node. The arm takes its own name; a device node resolves
``ur_hardware_interface`` in its own namespace, where the launch files start
the three side by side. So robots in different namespaces, or on different
masters, each have their own cell, and no parameter is needed.

Protocol: request and reply are tuples, one reply per request, in order.

    ('hello', VERSION)              -> ('hello', VERSION, {'time': s, 'timestep': s, 'ft_frame': name or None,
                                        'gripper': None or {'min_opening': m, 'max_opening': m,
                                                            'grip_force_range': (N, N)}})
    ('wrench',)                     -> ('wrench', time, (fx, fy, fz, tx, ty, tz), (ax, ay, az))
                                       the FT 300's reading (N, N m, sensor frame, the tool
                                       side on the sensor), no zero and no noise: those are the node's;
                                       and its accelerometer's (m/s^2, sensor frame, specific force)
    ('wrench_samples', period)      -> ('wrench_samples', time, [(t, wrench, acceleration), ...], dropped)
                                       the readings at every t that is a whole multiple of
                                       `period` (s, a whole number of timesteps) since the last
                                       such request, oldest first, t exact: what the FT 300's
                                       node publishes, one per period of simulated time stamped
                                       t, however late its process asks. The first request starts
                                       the keeping, one with another period starts it anew. At
                                       most 2000 wait (20 s at 10 ms); `dropped` counts the oldest
                                       lost beyond. A node started again receives what waited
                                       since its predecessor's last request: none lost or twice
    ('finger_samples', period)      -> ('finger_samples', time, [(t, state), ...], dropped, state)
                                       the fingers at every t that is a whole multiple of `period`
                                       (s) since the last such request, as wrench_samples: what the
                                       2F-140's node publishes, one status per period of simulated
                                       time, however late its process asks; each the state at the
                                       end of the control cycle that reached t; and the state now,
                                       for a node whose clock is ahead of the cell's last cycle
    ('finger', opening, speed, force) -> ('finger', time, state)
                                       command the fingers (m, m/s, N), then their state
    ('finger',)                     -> ('finger', time, state)     the state alone
    ('truth',)                      -> ('truth', time, {'contact_force': (fx, fy, fz),
                                        'contact_impulse': (ix, iy, iz),
                                        'objects': {name: ((x, y, z), (qw, qx, qy, qz))},
                                        'gripper_base': ((x, y, z), 3x3 rows) or None,
                                        'arm_position': (rad, ...), 'finger': state or None})
                                       MuJoCo's own figures, for tests and benchmarks to judge
                                       the interfaces by: the world's net contact force on the
                                       robot (N, world frame) and its impulse since the cell began
                                       (N s: two readings' difference over their time apart is the
                                       exact mean force between them), the objects' poses and the
                                       2F-140's base pose (world frame)
    anything else, or a failure     -> ('error', 'one line')

`time` is the cell's simulated time (s); `state` is the cell's FingerState as a dict
(opening, angle, velocity, torque, grip_force, target, ramp, closing, motion). A client
says hello first; a server of another VERSION answers ('error', ...).
"""

import hashlib
import os
import threading
import time
from multiprocessing import AuthenticationError
from multiprocessing.connection import Client, Listener

VERSION = 4
# ur_robot_driver's node, which holds the cell with physics.
ARM_NODE = 'ur_hardware_interface'
FOLDER = 'ur3_ft_gripper_cell'


def cell_address(master, arm_node, ros_home=None):
    """The socket of the cell that the arm node `arm_node` (resolved name) serves on `master`.

    `master`: what identifies the master, master_identity()'s.
    """
    if ros_home is None:
        import rospkg
        ros_home = rospkg.get_ros_home()
    key = hashlib.sha1(('%s %s' % (master, arm_node)).encode('utf-8')).hexdigest()[:16]
    return os.path.join(ros_home, FOLDER, key + '.sock')


def master_identity(caller):
    """'<port> <pid>' of the ROS master this process uses (rosgraph; `caller`: a node name for its API)."""
    import rosgraph
    from urllib.parse import urlparse
    master = rosgraph.Master(caller)
    return '%s %d' % (urlparse(master.master_uri).port, master.getPid())


def node_cell_address(rospy):
    """(address, resolved name) of the cell of ur_hardware_interface in this node's namespace (the arm's own
    too: a node's relative names resolve in its namespace)."""
    arm = rospy.resolve_name(ARM_NODE)
    return cell_address(master_identity(rospy.get_name()), arm), arm


# A device node waiting for the cell says so after this long (s): the arm's node builds the cell first.
QUIET_WAIT = 20.0


def wait_for_cell(rospy, who, poll=0.2):
    """A device node's CellClient of the cell of ur_hardware_interface in its namespace, once it serves.

    Warns once if it takes longer than QUIET_WAIT; None if the node shuts down meanwhile.
    """
    address, arm = node_cell_address(rospy)
    start, said = time.monotonic(), False
    while not rospy.is_shutdown():
        try:
            return CellClient(address)
        except LinkError as exc:
            if not said and time.monotonic() - start > QUIET_WAIT:
                said = True
                rospy.logwarn('%s: waiting for the physics cell of %s (%s); it serves once the arm runs with '
                              'physics (sim_arm.launch physics:=true)' % (who, arm, exc))
        time.sleep(poll)
    return None


def lost_cell(rospy, who, error):
    """A device node lost its cell: one fatal line, and the node shuts down (respawn starts it again)."""
    rospy.logfatal('%s: %s: exiting (launch files start it again with respawn="true")' % (who, error))
    rospy.signal_shutdown('the physics cell is gone')
    return error


class LinkError(RuntimeError):
    """The cell's side refused a request or is gone; the message is one line."""


class CellServer(object):
    """Serves `cell` at the AF_UNIX socket `path`, one thread per client.

    The arm's loop steps the cell holding `lock`; requests are answered holding it too.
    """

    def __init__(self, cell, path, authkey=None, lock=None):
        self.cell, self.path = cell, path
        self.lock = lock or threading.RLock()
        folder = os.path.dirname(os.path.abspath(path))
        os.makedirs(folder, mode=0o700, exist_ok=True)
        os.chmod(folder, 0o700)  # made earlier with other permissions: only this user may connect
        if os.path.exists(path):
            os.unlink(path)  # left by a process that died; a live server would still hold it open
        self._listener = Listener(path, family='AF_UNIX', authkey=authkey)
        self._closed = False
        self._thread = threading.Thread(target=self._accept, name='cell link', daemon=True)
        self._thread.start()

    def close(self):
        self._closed = True
        self._listener.close()
        if os.path.exists(self.path):
            os.unlink(self.path)

    def _accept(self):
        while not self._closed:
            try:
                connection = self._listener.accept()
            except (OSError, EOFError, AuthenticationError):
                if self._closed:
                    return
                continue  # a client that failed the key or hung up at once
            threading.Thread(target=self._serve, args=(connection,), name='cell link client',
                             daemon=True).start()

    def _serve(self, connection):
        with connection:
            while True:
                try:
                    request = connection.recv()
                except (EOFError, OSError):
                    return
                try:
                    reply = self.answer(request)
                except Exception as exc:  # one line back to the client; the server goes on
                    reply = ('error', '%s: %s' % (type(exc).__name__, ' '.join(str(exc).split())))
                connection.send(reply)

    def answer(self, request):
        """The reply to one request (see the module's protocol)."""
        if not isinstance(request, tuple) or not request:
            return ('error', 'a request is a tuple: (name, arguments...)')
        name, arguments = request[0], request[1:]
        cell = self.cell
        with self.lock:
            if name == 'hello':
                if arguments != (VERSION,):
                    return ('error', 'this cell speaks link version %d, not %r' % (VERSION, arguments))
                gripper = None
                if cell.gripper is not None:
                    gripper = dict(min_opening=cell.gripper.min_opening, max_opening=cell.gripper.max_opening,
                                   grip_force_range=tuple(cell.grip_force_range))
                return ('hello', VERSION, dict(time=cell.time, timestep=cell.timestep, ft_frame=cell.ft_frame,
                                               gripper=gripper))
            if name == 'wrench' and not arguments:
                return ('wrench', cell.time, tuple(float(v) for v in cell.wrench()),
                        tuple(float(v) for v in cell.accelerometer()))
            if name == 'wrench_samples' and len(arguments) == 1:
                period = float(arguments[0])
                if cell.wrench_sample_period != period:
                    cell.keep_wrench_samples(period)
                samples, dropped = cell.take_wrench_samples()
                return ('wrench_samples', cell.time, samples, dropped)
            if name == 'finger_samples' and len(arguments) == 1:
                period = float(arguments[0])
                if cell.finger_sample_period != period:
                    cell.keep_finger_samples(period)
                samples, dropped = cell.take_finger_samples()
                return ('finger_samples', cell.time, [(t, dict(vars(state))) for t, state in samples], dropped,
                        dict(vars(cell.finger())))
            if name == 'finger' and len(arguments) in (0, 3):
                if arguments:
                    cell.command_finger(*(float(v) for v in arguments))
                return ('finger', cell.time, dict(vars(cell.finger())))
            if name == 'truth' and not arguments:
                return ('truth', cell.time, _truth(cell))
        return ('error', 'unknown request %r: use hello, wrench, wrench_samples, finger, finger_samples or truth'
                % (request,))


def _truth(cell):
    def floats(values):
        return tuple(float(v) for v in values)
    base = None
    if cell.gripper is not None:
        position, rotation = cell.body_pose(cell.gripper_base)
        base = (floats(position), tuple(floats(row) for row in rotation))
    return dict(contact_force=floats(cell.contact_force()), contact_impulse=floats(cell.contact_impulse()),
                objects={name: tuple(floats(v) for v in cell.object_pose(name)) for name in cell.objects},
                gripper_base=base, arm_position=floats(cell.arm_position),
                finger=dict(vars(cell.finger())) if cell.gripper is not None else None)


class CellClient(object):
    """A node's side of the link: wrench(), finger(...) as the protocol says; LinkError if refused."""

    def __init__(self, path, authkey=None):
        try:
            self._connection = Client(path, family='AF_UNIX', authkey=authkey)
        except (OSError, EOFError) as exc:
            raise LinkError('no physics cell at %s (%s): start the arm with physics first' % (
                path, exc.strerror if isinstance(exc, OSError) and exc.strerror else exc)) from None
        except AuthenticationError:
            raise LinkError('the physics cell at %s refused this key: give both sides the same one' % path) from None
        self.info = self._ask('hello', VERSION)[2]

    def _ask(self, *request):
        try:
            self._connection.send(request)
            reply = self._connection.recv()
        except (OSError, EOFError) as exc:
            raise LinkError('the physics cell closed the link (%s)' % (exc,)) from None
        if reply[0] == 'error':
            raise LinkError(reply[1])
        return reply

    def wrench(self):
        """(time, (fx, fy, fz, tx, ty, tz), (ax, ay, az)) of the FT 300: its wrench and its accelerometer."""
        return self._ask('wrench')[1:]

    def wrench_samples(self, period):
        """(time, [(t, (fx, fy, fz, tx, ty, tz), (ax, ay, az)), ...], dropped): the FT 300's readings at every
        multiple t of `period` since the last call (the first call starts the keeping), and how many were
        dropped."""
        return self._ask('wrench_samples', period)[1:]

    def finger_samples(self, period):
        """(time, [(t, state dict), ...], dropped, state dict): the fingers at every multiple t of `period`
        since the last call (the first call starts the keeping), how many were dropped, and the state now."""
        return self._ask('finger_samples', period)[1:]

    def finger(self, opening=None, speed=None, force=None):
        """(time, state dict); with opening, speed and force, the fingers are commanded first."""
        request = ('finger',) if opening is None else ('finger', opening, speed, force)
        return self._ask(*request)[1:]

    def truth(self):
        """(time, dict) of MuJoCo's own figures (see the protocol)."""
        return self._ask('truth')[1:]

    def close(self):
        self._connection.close()
