"""An RTDE client written from UR's RTDE guide, for the tests; nothing of the package's own face.

Package: uint16 size (header included), uint8 type, payload; network byte
order. The types are the guide's letters; the field types' encodings are
the guide's table. Protocol 2 adds the output frequency and recipe ids in
the setup replies; protocol 1 clients get the controller's rate.
"""
import socket
import struct

FORMATS = {'BOOL': '?', 'UINT8': 'B', 'UINT32': 'I', 'UINT64': 'Q', 'INT32': 'i', 'DOUBLE': 'd',
           'VECTOR3D': '3d', 'VECTOR6D': '6d', 'VECTOR6INT32': '6i', 'VECTOR6UINT32': '6I'}


class Recipe(object):
    def __init__(self, recipe_id, names, types):
        self.id, self.names, self.types = recipe_id, names, types
        self.ok = recipe_id != 0 and all(t in FORMATS for t in types)
        self.format = '>B' + ''.join(FORMATS.get(t, '') for t in types)

    def decode(self, payload):
        flat = list(struct.unpack(self.format, payload))
        assert flat.pop(0) == self.id
        values = {}
        for name, kind in zip(self.names, self.types):
            width = int(FORMATS[kind][:-1] or 1)
            values[name] = flat[0] if width == 1 else flat[:width]
            del flat[:width]
        return values

    def encode(self, values):
        flat = [self.id]
        for name in self.names:
            value = values[name]
            flat.extend(value if isinstance(value, (list, tuple)) else [value])
        return struct.pack(self.format, *flat)


class RtdeClient(object):
    def __init__(self, port, address='127.0.0.1', timeout=10.0):
        self.socket = socket.create_connection((address, port), timeout=timeout)
        self.socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)  # as ur_rtde's client sends
        self.stream = self.socket.makefile('rb')
        self.protocol = 1
        self.outputs = None
        self.messages = []  # text messages from the controller: (level, text, source)

    def close(self):
        self.stream.close()
        self.socket.close()

    def send(self, kind, payload=b''):
        self.socket.sendall(struct.pack('>HB', len(payload) + 3, ord(kind)) + payload)

    def receive(self):
        """(type letter, payload) of the next package; text messages are kept aside."""
        while True:
            header = self.stream.read(3)
            if len(header) < 3:
                raise EOFError('the controller closed the connection')
            size, kind = struct.unpack('>HB', header)
            payload = self.stream.read(size - 3)
            if chr(kind) != 'M':
                return chr(kind), payload
            self.messages.append(self._text(payload))

    def _text(self, payload):
        if self.protocol == 1:
            return payload[0], payload[1:].decode(), ''
        end = 1 + payload[0]
        source_end = end + 1 + payload[end]
        return payload[source_end], payload[1:end].decode(), payload[end + 1:source_end].decode()

    def ask(self, kind, payload=b''):
        self.send(kind, payload)
        answer, reply = self.receive()
        assert answer == kind, 'asked %r, answered %r' % (kind, answer)
        return reply

    def negotiate(self, version=2):
        accepted = struct.unpack('>B', self.ask('V', struct.pack('>H', version)))[0] == 1
        if accepted:
            self.protocol = version
        return accepted

    def controller_version(self):
        return struct.unpack('>IIII', self.ask('v'))

    def setup_outputs(self, names, frequency=None):
        payload = ','.join(names).encode()
        if self.protocol == 2:
            payload = struct.pack('>d', frequency) + payload
        reply = self.ask('O', payload)
        self.outputs = Recipe(reply[0], names, reply[1:].decode().split(','))
        return self.outputs

    def setup_inputs(self, names):
        reply = self.ask('I', ','.join(names).encode())
        return Recipe(reply[0], names, reply[1:].decode().split(','))

    def start(self):
        return self.ask('S') == b'\x01'

    def pause(self):
        """Pause; data packages already on their way are read past."""
        self.send('P')
        while True:
            kind, payload = self.receive()
            if kind == 'P':
                return payload == b'\x01'
            assert kind == 'U', kind

    def data(self):
        kind, payload = self.receive()
        assert kind == 'U', kind
        return self.outputs.decode(payload)

    def write(self, recipe, values):
        self.send('U', recipe.encode(values))

    def say(self, text, source='test', level=3):
        if self.protocol == 1:
            self.send('M', struct.pack('>B', level) + text.encode())
        else:
            self.send('M', struct.pack('>B', len(text)) + text.encode() + struct.pack('>B', len(source)) +
                      source.encode() + struct.pack('>B', level))
