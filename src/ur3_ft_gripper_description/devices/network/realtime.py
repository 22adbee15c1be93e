"""The real-time client interface (TCP 30003): UR's state package at the control rate, and URScript in.

As UR's client interface document describes it: every control cycle (125 Hz
on a CB3, 500 Hz on an e-Series) each connected client gets one package, an
int32 size (counting itself) and then big-endian doubles, the fields of
config/ur_realtime_interface.yaml for the controller's software version.
Each field is the RTDE field of the same quantity (its `rtde` name), so both
faces read one robot; the slots UR reserves carry their fixed value. The
client may send URScript (script_text.py), as ur_rtde sends its control
program here.

The face knows nothing of the robot: `Realtime.cycle(read)` is called
after every control cycle with `read(rtde names) -> values` of that cycle,
and each program goes to `run(text)`.
"""

import socketserver
import struct

from ..sim_params import PackageFile
from . import listen
from .versions import available
from .script_text import ignore_input, read_programs
from ... import yaml_data

PORT = 30003
READ_ONLY_PORT = 30013  # its read-only twin (UR's overview of the client interfaces): nothing taken in
# A client that does not read: a second of packages at the fastest rate waits, then its connection ends.
SEND_QUEUE = 500


TABLE_FILE = PackageFile('config/ur_realtime_interface.yaml')


class Layout(object):
    """The package of one software version: `names` (RTDE fields read each cycle) and how to pack them."""

    def __init__(self, generation, version, path=None):
        with open(path or TABLE_FILE.path()) as stream:
            fields = [f for f in yaml_data.load(stream)['fields'] if available(f, generation, version)]
        self.names = [f['rtde'] for f in fields if f['rtde'] is not None]
        # Where each value goes: ('read', index in names, count) or ('fixed', value, count).
        self.parts = [('read', self.names.index(f['rtde']), f['count']) if f['rtde'] is not None
                      else ('fixed', float(f['value']), f['count']) for f in fields]
        doubles = sum(f['count'] for f in fields)
        self.size = 4 + 8 * doubles
        self.struct = struct.Struct('>i%dd' % doubles)

    def pack(self, values):
        flat = [self.size]
        for kind, what, count in self.parts:
            if kind == 'fixed':
                flat.extend([what] * count)
            else:
                value = values[what]
                flat.extend(float(v) for v in value) if count > 1 else flat.append(float(value))
        return self.struct.pack(*flat)


class Realtime(listen.Broadcast):
    """The connected clients of the real-time interface: a package each control cycle."""

    def cycle(self, read):
        self.send(read)


def serve(address, realtime, run, log, port=None, read_only=False):
    """A listening real-time interface at (address, port); `run(text)` runs a program the client sent.
    `read_only`: its twin (READ_ONLY_PORT), which sends the same and takes nothing in.
    The caller runs serve_forever() in a thread and shutdown() at the end (listen.ThreadingServer)."""
    face = 'real-time interface%s' % (' (read-only)' if read_only else '')
    if port is None:
        port = READ_ONLY_PORT if read_only else PORT

    class Connection(socketserver.BaseRequestHandler):
        def handle(self):
            client = '%s:%d' % self.client_address[:2]
            outbox = listen.Outbox(self.request, SEND_QUEUE, '%s: %s does not read its packages: '
                                   'its connection is closed' % (face, client), log)
            realtime.add(outbox.put)
            try:
                if read_only:
                    ignore_input(self.request, client, face, PORT, log)
                else:
                    read_programs(self.request, client, face, run, log)
            finally:
                realtime.remove(outbox.put)
                outbox.close()

    return listen.serve(face, address, port, Connection, log)
