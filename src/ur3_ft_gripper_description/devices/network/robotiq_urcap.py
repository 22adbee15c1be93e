"""The 2F-140 on Robotiq's gripper URCap socket (TCP 63352 on the robot): its text protocol; no ROS.

On a real cell the gripper hangs on the robot's tool connector and the
URCap serves it on the robot's address: SET writes request registers and is
answered "ack", GET reads one register and is answered "<VAR> <value>"
(config/robotiq_2f_urcap.yaml holds the variables, the registers behind
them and the port). Here the registers are the simulated gripper's own
(gripper_sim.RegisterGripper, through `gripper`), so a SET shows on the ROS
face's Robotiq2FGripperRobotInput and in RViz, and a GET reads what the ROS
face publishes.

Bad input costs nothing but the line: one log line naming the client and
the problem, no reply (as the gripper ignores what it cannot read), and the
connection stays open.
"""

import socketserver

from ..sim_params import PackageFile
from . import listen
from ... import yaml_data

MAX_LINE = 1024  # longer than any command: SET with every variable
TABLE_FILE = PackageFile('config/robotiq_2f_urcap.yaml')


def read_table(path=None):
    with open(path or TABLE_FILE.path()) as stream:
        return yaml_data.load(stream)


class UrcapGripper(object):
    """The protocol over `gripper` (command: dict of the request registers, set_command(dict), status() -> dict),
    each access under `lock`."""

    def __init__(self, table, gripper, lock):
        self.set_names, self.get_names = table['set'], table['get']
        self.gripper, self.lock = gripper, lock

    def reply(self, text):
        """(reply bytes, None) for one command line, or (None, the problem in words)."""
        words = text.split()
        if not words or words[0] not in ('SET', 'GET'):
            return None, 'not a command (SET <VAR> <value> ... or GET <VAR>): %r' % text[:80]
        if words[0] == 'GET':
            if len(words) != 2 or words[1] not in self.get_names:
                return None, 'GET takes one of %s: %r' % (' '.join(self.get_names), text[:80])
            register = self.get_names[words[1]]
            with self.lock:
                value = self.gripper.command[register] if register.startswith('r') else \
                    self.gripper.status()[register]
            return ('%s %d\n' % (words[1], value)).encode('ascii'), None
        pairs = words[1:]
        if not pairs or len(pairs) % 2:
            return None, 'SET takes pairs of <VAR> <value>: %r' % text[:80]
        writes = {}
        for name, value in zip(pairs[::2], pairs[1::2]):
            if name not in self.set_names:
                return None, 'SET %s: not one of %s' % (name, ' '.join(self.set_names))
            if not value.isdigit() or int(value) > 255:
                return None, 'SET %s %s: the value must be a whole number 0..255' % (name, value)
            if self.set_names[name] is not None:
                writes[self.set_names[name]] = int(value)
        with self.lock:
            command = dict(self.gripper.command)
            command.update(writes)
            self.gripper.set_command(command)
        return b'ack', None


def serve(address, protocol, log, port):
    """A listening URCap socket at (address, port) over `protocol` (a UrcapGripper); `log(text)` one line. The
    caller runs serve_forever() in a thread and shutdown() at the end (listen.ThreadingServer)."""

    class Session(socketserver.StreamRequestHandler):
        def handle(self):
            client = '%s:%d' % self.client_address[:2]
            while True:
                line = self.rfile.readline(MAX_LINE + 1)
                if not line:
                    return
                if len(line) > MAX_LINE:
                    log('gripper URCap socket: %s sent a line over %d bytes, not a command: its connection is '
                        'closed' % (client, MAX_LINE))
                    return
                try:
                    text = line.decode('ascii').strip()
                except UnicodeDecodeError:
                    log('gripper URCap socket: %s sent bytes that are not ASCII text: ignored' % client)
                    continue
                reply, problem = protocol.reply(text)
                if problem is not None:
                    log('gripper URCap socket: %s: %s; ignored, as the gripper ignores it' % (client, problem))
                    continue
                self.wfile.write(reply)

    return listen.serve('gripper URCap socket', address, port, Session, log)
