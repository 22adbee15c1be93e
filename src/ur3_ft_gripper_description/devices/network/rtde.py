"""RTDE, the Real-Time Data Exchange (TCP 30004): UR's binary protocol over the simulated robot; no ROS.

As UR's RTDE guide documents it. Every package is a header (uint16 size,
the header included, and uint8 type, network byte order) and a payload.
A client asks for a protocol version (1 or 2) and the controller's
version, then sets up recipes: an output recipe (the fields it reads, at a
frequency up to the controller's, in protocol 2) and input recipes (the
fields it writes). Each field name is answered with its type, or NOT_FOUND
when the controller has no such field, or IN_USE when another client
already writes that input. After START the controller sends a data
package of the output recipe at the recipe's frequency, on the
controller's clock; PAUSE stops it. The fields, their types and the
version that brought each are the guide's table (config/rtde_variables.yaml).

The face knows nothing of the robot: `Exchange.cycle(dt, read)` is called
after every control cycle with `read(names) -> values` of that cycle, and
a client's input data package goes to `write({name: value})`.

Bad input costs the client its connection, never the robot: a package
whose header or payload the protocol cannot read, or of an unknown type,
gets one log line naming the client, and only that connection closes.
"""

import socketserver
import struct
import threading

from ..sim_params import PackageFile
from . import listen
from .versions import available
from ... import yaml_data

PORT = 30004
HEADER = struct.Struct('>HB')
REQUEST_PROTOCOL_VERSION = ord('V')
GET_URCONTROL_VERSION = ord('v')
TEXT_MESSAGE = ord('M')
DATA_PACKAGE = ord('U')
SETUP_OUTPUTS = ord('O')
SETUP_INPUTS = ord('I')
START = ord('S')
PAUSE = ord('P')
PROTOCOL_VERSIONS = (1, 2)
# The field types and their encodings (struct format, network byte order).
TYPE_FORMAT = {'BOOL': '?', 'UINT8': 'B', 'UINT32': 'I', 'UINT64': 'Q', 'INT32': 'i', 'DOUBLE': 'd',
               'VECTOR3D': '3d', 'VECTOR6D': '6d', 'VECTOR6INT32': '6i', 'VECTOR6UINT32': '6I'}
NOT_FOUND, IN_USE = 'NOT_FOUND', 'IN_USE'
# The guide's limits: a recipe's list of names, input recipes on a connection.
MAX_RECIPE_TEXT = 2048
MAX_INPUT_RECIPES = 255
# Packages waiting for a client that reads slower than it asked. The guide: a client must read
# regularly, and the controller closes the connection when its send buffer overflows (it never
# waits for a client); here the buffer is a second's worth of data at the fastest rate.
SEND_QUEUE = 500


def zero(kind):
    """The zero value of a field type."""
    fmt = TYPE_FORMAT[kind]
    value = False if fmt == '?' else 0.0 if fmt[-1] == 'd' else 0
    return [value] * int(fmt[:-1]) if len(fmt) > 1 else value


class ProtocolError(ValueError):
    """A package the protocol cannot read: the client's connection ends, with this one line."""


TABLE_FILE = PackageFile('config/rtde_variables.yaml')


def read_table(generation, version, path=None):
    """{'outputs': {name: type}, 'inputs': {name: type}}: the guide's fields a controller of `generation`
    ('cb3' or 'e_series') at software `version` (a tuple) has, register ranges expanded."""
    with open(path or TABLE_FILE.path()) as stream:
        data = yaml_data.load(stream)
    table = {}
    for direction in ('outputs', 'inputs'):
        fields = table[direction] = {}
        for name, entry in data[direction].items():
            if '{n}' not in name:
                if available(entry, generation, version):
                    fields[name] = entry['type']
                continue
            for span in entry['ranges']:
                if available(dict(span, removed=entry.get('removed')), generation, version):
                    for index in range(span['first'], span['last'] + 1):
                        fields[name.replace('{n}', str(index))] = entry['type']
    return table


class Recipe(object):
    """A recipe: its id, its fields' names and types, and their packing."""

    def __init__(self, recipe_id, names, types):
        self.id, self.names, self.types = recipe_id, names, types
        self.struct = struct.Struct('>B' + ''.join(TYPE_FORMAT[t] for t in types))

    def pack(self, values):
        flat = [self.id]
        for value in values:
            flat.extend(value if isinstance(value, (list, tuple)) else (value,))
        return self.struct.pack(*flat)

    def unpack(self, payload):
        """{name: value} of a data package's payload (its recipe id first)."""
        flat = list(self.struct.unpack(payload))[1:]
        values = {}
        for name, kind in zip(self.names, self.types):
            width = int(TYPE_FORMAT[kind][:-1] or 1)
            values[name] = flat[0] if width == 1 else flat[:width]
            del flat[:width]
        return values


def packet(kind, payload=b''):
    return HEADER.pack(HEADER.size + len(payload), kind) + payload


class Exchange(object):
    """The controller's RTDE: its fields, the clients' sessions and their recipes, the data each cycle.

    `version`: the controller software (major, minor, bugfix, build); `max_frequency`: its control rate
    (Hz); `write(values)` applies an input data package to the robot; `log(text)` one line.
    """

    def __init__(self, fields, version, max_frequency, write, log):
        self.fields, self.version, self.max_frequency = fields, tuple(version), float(max_frequency)
        self.write, self.log = write, log
        self.lock = threading.Lock()
        self.sessions = []
        self.owners = {}  # input field name -> the Session that set it up

    def session(self, send, client, hung_up=lambda: False):
        """A client's session; `hung_up()` tells whether the client has closed its connection."""
        session = Session(self, send, client, hung_up)
        with self.lock:
            self.sessions.append(session)
        return session

    def close(self, session):
        with self.lock:
            self._release(session)

    def _release(self, session):
        if session in self.sessions:
            self.sessions.remove(session)
        for name in [n for n, owner in self.owners.items() if owner is session]:
            del self.owners[name]

    def claim_inputs(self, session, names):
        """The types of `names` for an input recipe of `session`, each NOT_FOUND, IN_USE (another client
        writes it) or its type; whether all are taken for `session`."""
        with self.lock:
            # A client that closed its connection writes nothing more, though its session's thread may not
            # have run since: its inputs go to the next client at once (ur_rtde's IO interface, closed, then
            # its control interface asks for the same registers).
            for owner in {self.owners[name] for name in names if name in self.owners} - {session}:
                if owner.hung_up():
                    self._release(owner)
            types = [self.fields['inputs'].get(name, NOT_FOUND) for name in names]
            types = [IN_USE if kind != NOT_FOUND and self.owners.get(name, session) is not session else kind
                     for name, kind in zip(names, types)]
            if NOT_FOUND in types or IN_USE in types:
                return types, False
            for name in names:
                self.owners[name] = session
            return types, True

    def cycle(self, read):
        """After a control cycle: each started session whose turn it is gets a data package."""
        with self.lock:
            due = [s for s in self.sessions if s.due()]
        for session in due:
            recipe = session.outputs
            data = recipe.pack(read(recipe.names))
            # Protocol 1's data packages carry no recipe id: it has one output recipe and no ids.
            session.send(packet(DATA_PACKAGE, data if session.protocol == 2 else data[1:]))


class Session(object):
    """One client's protocol state; `receive(kind, payload)` answers, and data goes out, through `send(bytes)`."""

    def __init__(self, exchange, send, client, hung_up):
        self.exchange, self.send, self.client, self.hung_up = exchange, send, client, hung_up
        self.protocol = 1
        self.outputs = None          # Recipe
        self.inputs = {}             # recipe id -> Recipe
        self.every, self.cycles = 1, 0  # a data package every `every` cycles; cycles since the last
        self.started = False

    def due(self):
        if not self.started:
            return False
        self.cycles += 1
        if self.cycles < self.every:
            return False
        self.cycles = 0
        return True

    def receive(self, kind, payload):
        handler = {REQUEST_PROTOCOL_VERSION: self._protocol_version, GET_URCONTROL_VERSION: self._controller_version,
                   SETUP_OUTPUTS: self._setup_outputs, SETUP_INPUTS: self._setup_inputs, START: self._start,
                   PAUSE: self._pause, DATA_PACKAGE: self._data, TEXT_MESSAGE: self._text}.get(kind)
        if handler is None:
            raise ProtocolError('a package of unknown type %d' % kind)
        try:
            handler(payload)
        except (struct.error, UnicodeDecodeError, IndexError) as error:
            raise ProtocolError('a %r package the protocol cannot read (%s)' % (chr(kind), error)) from None

    def _protocol_version(self, payload):
        version, = struct.unpack('>H', payload)
        accepted = version in PROTOCOL_VERSIONS
        if accepted:
            self.protocol = version
        self.send(packet(REQUEST_PROTOCOL_VERSION, struct.pack('>B', accepted)))

    def _controller_version(self, payload):
        self.send(packet(GET_URCONTROL_VERSION, struct.pack('>IIII', *self.exchange.version)))

    def _names(self, payload):
        if len(payload) > MAX_RECIPE_TEXT:
            raise ProtocolError('a recipe of %d bytes of names, over the guide\'s %d' % (len(payload), MAX_RECIPE_TEXT))
        # Clients end the list with a comma, or not.
        return [name.strip() for name in payload.decode('utf-8').split(',') if name.strip()]

    def _setup_outputs(self, payload):
        """The one output recipe (a new one replaces it); refused while started, for an unknown name or a
        frequency beyond the controller's, with recipe id 0 (protocol 1: no id in the reply)."""
        if self.protocol == 2:
            frequency, = struct.unpack_from('>d', payload)
            names = self._names(payload[8:])
        else:
            frequency, names = self.exchange.max_frequency, self._names(payload)
        types = [self.exchange.fields['outputs'].get(name, NOT_FOUND) for name in names]
        ok = bool(names) and NOT_FOUND not in types and 0.0 < frequency <= self.exchange.max_frequency and \
            not self.started
        if ok:
            self.outputs = Recipe(1, names, types)
            # The guide: a package every floor(controller's rate / frequency) cycles.
            self.every = max(1, int(self.exchange.max_frequency / frequency + 1e-9))
        reply = ','.join(types).encode('utf-8')
        self.send(packet(SETUP_OUTPUTS, reply if self.protocol == 1 else struct.pack('>B', ok) + reply))

    def _setup_inputs(self, payload):
        """An input recipe, numbered from 1 on each connection; id 0 if refused."""
        names = self._names(payload)
        types, ok = self.exchange.claim_inputs(self, names)
        recipe_id = len(self.inputs) + 1 if ok and names and len(self.inputs) < MAX_INPUT_RECIPES else 0
        if recipe_id:
            self.inputs[recipe_id] = Recipe(recipe_id, names, types)
        self.send(packet(SETUP_INPUTS, struct.pack('>B', recipe_id) + ','.join(types).encode('utf-8')))

    def _start(self, payload):
        """Start the output data; refused without an output recipe (inputs need no start)."""
        self.started = self.outputs is not None
        self.cycles = self.every - 1  # the first data package comes with the next cycle
        self.send(packet(START, struct.pack('>B', self.started)))

    def _pause(self, payload):
        self.started = False
        self.send(packet(PAUSE, struct.pack('>B', True)))

    def _data(self, payload):
        recipe = self.inputs.get(payload[0])
        if recipe is None:
            raise ProtocolError('a data package of input recipe %d, which it has not set up' % payload[0])
        self.exchange.write(recipe.unpack(payload))

    def _text(self, payload):
        if self.protocol == 1:
            level, text, source = payload[0], payload[1:], b''
        else:
            end = 1 + payload[0]
            text = payload[1:end]
            source = payload[end + 1:end + 1 + payload[end]]
            level = payload[end + 1 + payload[end]]
        self.exchange.log('rtde: %s says (level %d) %s%s' % (self.client, level, source.decode('utf-8', 'replace') +
                                                            ': ' if source else '', text.decode('utf-8', 'replace')))


def serve(address, exchange, log, port=PORT):
    """A listening RTDE server at (address, port) over `exchange`; the caller runs serve_forever() in a
    thread and shutdown() at the end (listen.ThreadingServer)."""

    class Connection(socketserver.StreamRequestHandler):
        def handle(self):
            client = '%s:%d' % self.client_address[:2]
            outbox = listen.Outbox(self.request, SEND_QUEUE, 'rtde: %s reads slower than the frequency it asked for: '
                                   'its connection is closed' % client, log)
            session = exchange.session(outbox.put, client, lambda: listen.peer_hung_up(self.request))
            try:
                self._read(session, client)
            finally:
                exchange.close(session)
                outbox.close()

        def _read(self, session, client):
            while True:
                header = self.rfile.read(HEADER.size)
                if len(header) < HEADER.size:
                    return
                size, kind = HEADER.unpack(header)
                payload = self.rfile.read(max(size - HEADER.size, 0))
                try:
                    if size < HEADER.size or len(payload) < size - HEADER.size:
                        raise ProtocolError('a package header of size %d' % size)
                    session.receive(kind, payload)
                except ProtocolError as error:
                    log('rtde: %s sent %s: its connection is closed' % (client, error))
                    return

    return listen.serve('RTDE', address, port, Connection, log)
