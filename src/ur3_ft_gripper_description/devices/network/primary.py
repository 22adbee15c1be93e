"""The primary and secondary client interfaces (TCP 30001, 30002): UR's robot state at 10 Hz, URScript in.

As UR's client interface document describes them. A client is first sent
the version message (a robot message of type VERSION: "URControl", the
software version, a build date), then a robot state package every 0.1 s of
the controller's time: the sub-packages of config/ur_primary_interface.yaml
for the generation and software version, in the order the controller sends
them, each value from its `source` (an RTDE field, a quantity of the
controller, or a constant). Both ports send the same; both take URScript
(script_text.py), and the primary interface also takes the few controller
commands ur_client_library sends as text (PRIMARY_COMMANDS).

The face knows nothing of the robot: `Primary.cycle(dt, read)` is called
after every control cycle with `read(names) -> values` of that cycle;
programs go to `run(text)` and the controller commands to `dashboard(command)`.
"""

import math
import socketserver
import struct

from ..sim_params import PackageFile
from . import listen
from .versions import available
from .script_text import ignore_input, read_programs
from ... import yaml_data

PORTS = {'primary': 30001, 'secondary': 30002}
# The read-only twins (UR's client interface document): the same packages, nothing taken in.
READ_ONLY_PORTS = {'primary': 30011, 'secondary': 30012}
ROBOT_STATE, ROBOT_MESSAGE = 16, 20
TEXT, VERSION, KEY, RUNTIME_EXCEPTION = 0, 3, 7, 10  # robot message types
# Robot message sources as ur_client_library's captures have them: the controller's own messages, and
# the runtime's (runtime exceptions).
SOURCE_CONTROLLER, SOURCE_RUNTIME = -2, -3
# The KEY message's title of each program event, literally as the controller sends it.
KEY_TITLES = {'PROGRAM_STARTED': 'PROGRAM_XXX_STARTED', 'PROGRAM_STOPPED': 'PROGRAM_XXX_STOPPED'}
PROJECT_NAME, BUILD_DATE = b'URControl', b'simulated'
STATE_PERIOD = 0.1  # s of the controller's time: 10 Hz
TYPES = {'int8': 'b', 'uint8': 'B', 'bool': '?', 'int16': 'h', 'int32': 'i', 'uint32': 'I', 'uint64': 'Q',
         'float': 'f', 'double': 'd'}
# Text the primary interface takes beside URScript, as ur_client_library sends it: the Dashboard Server's
# command of the same effect.
PRIMARY_COMMANDS = {'power on': 'power on', 'power off': 'power off', 'set robotmode run': 'brake release',
                    'set unlock protective stop': 'unlock protective stop', 'stop program': 'stop'}
# A client that does not read: 10 s of states wait, then its connection ends.
SEND_QUEUE = 100


TABLE_FILE = PackageFile('config/ur_primary_interface.yaml')


def _source(source, element):
    """('read', name, element index or None) or ('const', value) of a field's `source`."""
    if not isinstance(source, str):
        return 'const', source
    if source.endswith(']'):
        name, index = source[:-1].split('[')
        return 'read', name, int(index)
    return 'read', source, element


class StateLayout(object):
    """The robot state package of one generation and software version: `names` read, and their packing."""

    def __init__(self, generation, version, path=None):
        with open(path or TABLE_FILE.path()) as stream:
            table = yaml_data.load(stream)
        self.names, self.packages = [], []
        for name in table['robot_state_order'][generation]:
            package = table['robot_state_sub_packages'][name]
            repeat = package.get('repeat', 1)
            fields = [f for f in package.get('per_joint') or package['fields']
                      if available(f, generation, version) and 'only_if' not in f]
            fmt, items = '>iB', []
            for joint in range(repeat):
                for field in fields:
                    kind = field['type']
                    if kind.startswith('char['):  # bytes UR keeps for itself: zeros
                        fmt += kind[5:-1] + 's'
                        items.append(('const', b'', None))
                        continue
                    count = field.get('count', 1)
                    for element in range(count):
                        fmt += TYPES[kind]
                        item = _source(field['source'], joint if repeat > 1 else element if count > 1 else None)
                        if item[0] == 'read' and item[1] not in self.names:
                            self.names.append(item[1])
                        items.append(item + (kind,))
            self.packages.append((package['id'], struct.Struct(fmt), items))

    def pack(self, values):
        read = dict(zip(self.names, values))
        data = []
        for package_id, layout, items in self.packages:
            flat = [layout.size, package_id]
            for item in items:
                if item[0] == 'const':
                    value = item[1]
                else:
                    value = read[item[1]]
                    value = value if item[2] is None else value[item[2]]
                flat.append(_cast(value, item[-1]))
            data.append(layout.pack(*flat))
        body = b''.join(data)
        return struct.pack('>iB', 5 + len(body), ROBOT_STATE) + body


def _cast(value, kind):
    if kind in ('float', 'double'):
        return float(value)
    if kind == 'bool':
        return bool(value)
    if kind is None:
        return value
    return int(value)


def robot_message(kind, source, body, timestamp=0):
    """A robot message package: its header (time stamp, source, type), then `body`."""
    data = struct.pack('>QbB', timestamp, source, kind) + body
    return struct.pack('>iB', 5 + len(data), ROBOT_MESSAGE) + data


def version_message(version, timestamp=0):
    """The robot message of type VERSION for software `version` (major, minor, bugfix, build)."""
    return robot_message(VERSION, SOURCE_CONTROLLER, struct.pack('>b', len(PROJECT_NAME)) + PROJECT_NAME +
                         struct.pack('>BBii', *version[:4]) + BUILD_DATE, timestamp)


def key_message(title, text, timestamp=0):
    """A KEY robot message, as the controller announces a program: title PROGRAM_XXX_STARTED or
    PROGRAM_XXX_STOPPED, text the program's name (ur_client_library's sendScriptBlocking waits for both)."""
    title = title.encode('utf-8')
    return robot_message(KEY, SOURCE_CONTROLLER, struct.pack('>iiB', 0, 0, len(title)) + title + text.encode('utf-8'),
                         timestamp)


def text_message(text, timestamp=0):
    """A TEXT robot message: a running program's textmsg, its text all the body. No capture of one gives its
    source; the runtime's, as on the runtime's exceptions."""
    return robot_message(TEXT, SOURCE_RUNTIME, text.encode('utf-8'), timestamp)


def runtime_exception_message(line, column, text, timestamp=0):
    """A RUNTIME_EXCEPTION robot message: where the program failed, and why."""
    return robot_message(RUNTIME_EXCEPTION, SOURCE_RUNTIME, struct.pack('>II', line, column) + text.encode('utf-8'),
                         timestamp)


class Primary(listen.Broadcast):
    """The clients of both interfaces and the robot state each 0.1 s of the controller's time sends them."""

    def __init__(self, layout, version):
        super().__init__(layout)
        self.version = tuple(version)
        self.time = 0.0  # s of the controller's time
        self.message_clients = []  # the primary interface's clients: its robot messages too

    def tell(self, message):
        """A robot message to the primary interface's clients (the secondary sends only states)."""
        with self.lock:
            clients = list(self.message_clients)
        for send in clients:
            send(message)

    def cycle(self, dt, read, events=()):
        """After a control cycle of `dt` s: its program events as robot messages (('PROGRAM_STARTED' or
        'PROGRAM_STOPPED', name), ('TEXT', text) or ('RUNTIME_EXCEPTION', line, column, text)), and a state on
        the cycle that reaches each tenth of a second."""
        stamp = int(round((self.time + dt) * 1000.0))
        for event in events:
            if event[0] == 'RUNTIME_EXCEPTION':
                self.tell(runtime_exception_message(*event[1:], timestamp=stamp))
            elif event[0] == 'TEXT':
                self.tell(text_message(event[1], timestamp=stamp))
            else:
                self.tell(key_message(KEY_TITLES[event[0]], event[1], timestamp=stamp))
        before, self.time = self.time, self.time + dt
        if math.floor(self.time / STATE_PERIOD + 1e-9) == math.floor(before / STATE_PERIOD + 1e-9):
            return
        self.send(read)


def serve(name, address, primary, run, dashboard, log, port=None, read_only=False):
    """A listening primary ('primary') or secondary ('secondary') interface at (address, port) over
    `primary`; `run(text)` runs a program, `dashboard(command)` a controller command (primary only).
    `read_only`: its twin on READ_ONLY_PORTS, which sends the same and takes nothing in.
    The caller runs serve_forever() in a thread and shutdown() at the end (listen.ThreadingServer)."""
    face = '%s interface%s' % (name, ' (read-only)' if read_only else '')
    commands = PRIMARY_COMMANDS if name == 'primary' else {}
    if port is None:
        port = (READ_ONLY_PORTS if read_only else PORTS)[name]

    def take(text):
        command = commands.get(text.strip())
        if command is not None:
            dashboard(command)
        else:
            run(text)

    class Connection(socketserver.BaseRequestHandler):
        def handle(self):
            client = '%s:%d' % self.client_address[:2]
            outbox = listen.Outbox(self.request, SEND_QUEUE, '%s: %s does not read its packages: its connection '
                                   'is closed' % (face, client), log)
            outbox.put(version_message(primary.version))
            primary.add(outbox.put)
            if name == 'primary':
                with primary.lock:
                    primary.message_clients.append(outbox.put)
            try:
                if read_only:
                    ignore_input(self.request, client, face, PORTS[name], log)
                else:
                    read_programs(self.request, client, face, take, log)
            finally:
                primary.remove(outbox.put)
                if name == 'primary':
                    with primary.lock:
                        primary.message_clients.remove(outbox.put)
                outbox.close()

    return listen.serve(face, address, port, Connection, log)
