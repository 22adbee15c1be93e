"""The 2F-140 on Modbus: RTU on a pseudo-terminal, as on the gripper's RS-485 line, and TCP, as Robotiq's
gateway serves it; no ROS.

What the gripper answers is the table's (config/robotiq_2f_modbus.yaml: slave id, the two register
blocks, the function codes, the bits of each byte); the framing is modbus_tk's (its RTU and TCP
queries: the slave id, the CRC, the MBAP header). The registers are the simulated gripper's own
(gripper_sim.RegisterGripper, through `gripper`), so a write shows on the ROS face's
Robotiq2FGripperRobotInput and in RViz, and a read returns what the ROS face publishes.

Bad input, as a Modbus device meets it: a frame with a wrong CRC or for another slave gets no reply; a
request the gripper cannot serve gets the protocol's exception reply; each costs one log line, and the
line (or connection) goes on.
"""

import socketserver
import struct
import threading

from ..sim_params import PackageFile
from . import listen
from .modbus_line import MAX_ADU, PseudoTerminal, RegisterDevice, RtuSlave, framings
from ... import yaml_data

TABLE_FILE = PackageFile('config/robotiq_2f_modbus.yaml')


def read_table(path=None):
    with open(path or TABLE_FILE.path()) as stream:
        return yaml_data.load(stream)


class Layout(object):
    """The bytes of one register block: {byte: {name: [first bit, bit count]}} <-> {name: value}."""

    def __init__(self, byte_fields, registers):
        self.size = 2 * registers
        self.fields = [(int(byte), name, first, (1 << count) - 1)
                       for byte, names in byte_fields.items() for name, (first, count) in names.items()]

    def registers(self, values):
        data = bytearray(self.size)
        for byte, name, first, mask in self.fields:
            data[byte] |= (int(values[name]) & mask) << first
        return list(struct.unpack('>%dH' % (self.size // 2), bytes(data)))

    def values(self, registers):
        data = struct.pack('>%dH' % len(registers), *registers)
        return {name: (data[byte] >> first) & mask for byte, name, first, mask in self.fields}


class ModbusGripper(RegisterDevice):
    """The gripper's Modbus application layer over `gripper` (command: dict of the request registers,
    set_command(dict), status() -> dict), each access under `lock`; `face` 'rtu' or 'tcp' picks the
    table's register addresses."""

    who = 'the gripper'

    def __init__(self, table, gripper, lock, face):
        super().__init__(table)
        self.gripper, self.lock = gripper, lock
        count = table['registers']
        self.request = Layout(table['request_bytes'], count)
        self.status = Layout(table['status_bytes'], count)
        self.request_first = table[face]['request_register']
        self.status_first = table[face]['status_register']
        self.count = count

    def _block(self, address, count):
        """'request' or 'status', the block that holds registers address .. address + count - 1, or None.
        Where the two blocks share their addresses (the gateway's map), reads are of the status."""
        for name, first in (('status', self.status_first), ('request', self.request_first)):
            if first <= address and address + count <= first + self.count:
                return name
        return None

    def read(self, address, count):
        block = self._block(address, count)
        if block is None:
            return None
        first = self.status_first if block == 'status' else self.request_first
        with self.lock:
            registers = self.status.registers(self.gripper.status()) if block == 'status' else \
                self.request.registers(self.gripper.command)
        return registers[address - first:address - first + count]

    def write(self, address, values):
        first = self.request_first
        if not (first <= address and address + len(values) <= first + self.count):
            return 'illegal_data_address', self.outside('a write of', address, len(values), True)
        with self.lock:
            registers = self.request.registers(self.gripper.command)
            registers[address - first:address - first + len(values)] = values
            command = dict(self.gripper.command)
            command.update(self.request.values(registers))
            self.gripper.set_command(command)
        return None

    def outside(self, what, address, count, writing):
        blocks = 'the requests at 0x%04X' % self.request_first if writing else \
            'the requests at 0x%04X or the status at 0x%04X' % (self.request_first, self.status_first)
        return '%s %d registers at 0x%04X is outside %s (%d registers each)' % (what, count, address, blocks,
                                                                             self.count)


def serve_rtu(table, gripper, lock, log, link=None):
    """The gripper on a pseudo-terminal, serving in a thread of its own; the PseudoTerminal."""
    device = RtuSlave(ModbusGripper(table, gripper, lock, 'rtu'), table['rtu']['slave_id'], '2F-140 Modbus RTU', log)
    return PseudoTerminal(device, table['rtu']['frame_gap'], link, "the 2F-140's").start('2F-140 Modbus RTU')


def serve_tcp(table, gripper, lock, log, address, port=None):
    """The gripper behind a Modbus TCP gateway at (address, port), serving in threads of its own; the
    listen.ThreadingServer (shutdown() to end); listen.ListenError (one line) when it cannot listen."""
    protocol = ModbusGripper(table, gripper, lock, 'tcp')
    query_class = framings()[1]

    class Session(socketserver.StreamRequestHandler):
        def handle(self):
            client = '%s:%d' % self.client_address[:2]
            while True:
                header = self.rfile.read(7)
                if len(header) < 7:
                    return
                length = struct.unpack('>H', header[4:6])[0]
                if not 2 <= length <= MAX_ADU - 6:
                    log('2F-140 Modbus TCP: %s sent a header of length %d, not a Modbus frame: its connection is '
                        'closed' % (client, length))
                    return
                body = self.rfile.read(length - 1)
                if len(body) < length - 1:
                    return
                query = query_class()
                try:
                    _, pdu = query.parse_request(header + body)
                except Exception as exc:  # modbus_tk's invalid-request errors
                    log('2F-140 Modbus TCP: %s sent a frame the gateway cannot read (%s); no reply' % (client, exc))
                    continue
                response, problem = protocol.reply(pdu)
                if problem is not None:
                    log('2F-140 Modbus TCP: %s: %s; exception %d replied' % (client, problem, response[1]))
                self.wfile.write(query.build_response(response))

    server = listen.serve('2F-140 Modbus TCP', address, table['tcp']['port'] if port is None else port, Session, log)
    threading.Thread(target=server.serve_forever, name='2F-140 Modbus TCP', daemon=True).start()
    return server

