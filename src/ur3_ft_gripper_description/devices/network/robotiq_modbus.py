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

import yaml

from ..sim_params import PackageFile
from . import listen
from .modbus_line import MAX_ADU, ModbusUnavailable, PseudoTerminal, framings

TABLE_FILE = PackageFile('config/robotiq_2f_modbus.yaml')


def read_table(path=None):
    with open(path or TABLE_FILE.path()) as stream:
        return yaml.safe_load(stream)


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


class ModbusGripper(object):
    """The gripper's Modbus application layer over `gripper` (command: dict of the request registers,
    set_command(dict), status() -> dict), each access under `lock`; `face` 'rtu' or 'tcp' picks the
    table's register addresses."""

    def __init__(self, table, gripper, lock, face):
        self.gripper, self.lock = gripper, lock
        count = table['registers']
        self.request = Layout(table['request_bytes'], count)
        self.status = Layout(table['status_bytes'], count)
        self.request_first = table[face]['request_register']
        self.status_first = table[face]['status_register']
        self.count = count
        self.codes = {int(code): name for code, name in table['function_codes'].items()}
        self.exceptions = table['exceptions']

    # -- the blocks ---------------------------------------------------------------

    def _block(self, address, count):
        """'request' or 'status', the block that holds registers address .. address + count - 1, or None.
        Where the two blocks share their addresses (the gateway's map), reads are of the status."""
        for name, first in (('status', self.status_first), ('request', self.request_first)):
            if first <= address and address + count <= first + self.count:
                return name
        return None

    def _read(self, address, count):
        block = self._block(address, count)
        if block is None:
            return None
        first = self.status_first if block == 'status' else self.request_first
        with self.lock:
            registers = self.status.registers(self.gripper.status()) if block == 'status' else \
                self.request.registers(self.gripper.command)
        return registers[address - first:address - first + count]

    def _write(self, address, values):
        first = self.request_first
        if not (first <= address and address + len(values) <= first + self.count):
            return False
        with self.lock:
            registers = self.request.registers(self.gripper.command)
            registers[address - first:address - first + len(values)] = values
            command = dict(self.gripper.command)
            command.update(self.request.values(registers))
            self.gripper.set_command(command)
        return True

    # -- requests -----------------------------------------------------------------

    def _exception(self, code, name, problem):
        return struct.pack('>BB', code | 0x80, self.exceptions[name]), problem

    def reply(self, pdu):
        """(response PDU, the problem in words or None) for one request PDU."""
        code = pdu[0]
        kind = self.codes.get(code)
        if kind is None:
            return self._exception(code, 'illegal_function', 'function code %d is not one the gripper answers '
                                   '(%s)' % (code, ', '.join(str(c) for c in sorted(self.codes))))
        return getattr(self, '_' + kind)(code, pdu[1:])

    def _read_registers(self, code, body):
        if len(body) != 4:
            return self._exception(code, 'illegal_data_value', 'a read of %d bytes, not 4' % len(body))
        address, count = struct.unpack('>HH', body)
        if not 1 <= count <= 125:
            return self._exception(code, 'illegal_data_value', 'a read of %d registers (1..125)' % count)
        registers = self._read(address, count)
        if registers is None:
            return self._exception(code, 'illegal_data_address', self._outside('a read of', address, count))
        return struct.pack('>BB%dH' % count, code, 2 * count, *registers), None

    _read_holding_registers = _read_input_registers = _read_registers

    def _write_multiple_registers(self, code, body):
        if len(body) < 5 or len(body) != 5 + body[4]:
            return self._exception(code, 'illegal_data_value', 'a write whose length does not match its byte '
                                   'count')
        address, count, size = struct.unpack('>HHB', body[:5])
        if not 1 <= count <= 123 or size != 2 * count:
            return self._exception(code, 'illegal_data_value', 'a write of %d registers in %d bytes' % (count, size))
        if not self._write(address, list(struct.unpack('>%dH' % count, body[5:]))):
            return self._exception(code, 'illegal_data_address', self._outside('a write of', address, count,
                                                                              writing=True))
        return struct.pack('>BHH', code, address, count), None

    def _read_write_multiple_registers(self, code, body):
        if len(body) < 9 or len(body) != 9 + body[8]:
            return self._exception(code, 'illegal_data_value', 'a read/write whose length does not match its '
                                   'byte count')
        read_address, read_count, write_address, write_count, size = struct.unpack('>HHHHB', body[:9])
        if not 1 <= read_count <= 125 or not 1 <= write_count <= 121 or size != 2 * write_count:
            return self._exception(code, 'illegal_data_value', 'a read of %d and a write of %d registers in %d '
                                   'bytes' % (read_count, write_count, size))
        if self._block(read_address, read_count) is None:
            return self._exception(code, 'illegal_data_address', self._outside('a read of', read_address,
                                                                              read_count))
        # The write first, then the read (the protocol's order for function 23).
        if not self._write(write_address, list(struct.unpack('>%dH' % write_count, body[9:]))):
            return self._exception(code, 'illegal_data_address', self._outside('a write of', write_address,
                                                                              write_count, writing=True))
        registers = self._read(read_address, read_count)
        return struct.pack('>BB%dH' % read_count, code, 2 * read_count, *registers), None

    def _outside(self, what, address, count, writing=False):
        blocks = 'the requests at 0x%04X' % self.request_first if writing else \
            'the requests at 0x%04X or the status at 0x%04X' % (self.request_first, self.status_first)
        return '%s %d registers at 0x%04X is outside %s (%d registers each)' % (what, count, address, blocks,
                                                                             self.count)


class RtuDevice(object):
    """The gripper as a Modbus RTU slave: frames in, frames out (bytes), through modbus_tk's RTU query."""

    def __init__(self, table, gripper, lock, log):
        self.protocol = ModbusGripper(table, gripper, lock, 'rtu')
        self.slave_id = table['rtu']['slave_id']
        self.query_class = framings()[0]
        self.log = log

    def answer(self, frame):
        """The response frame to one request frame, or b'' (none: a bad CRC, another slave, a broadcast)."""
        if len(frame) > MAX_ADU:
            self.log('2F-140 Modbus RTU: %d bytes without a pause, longer than any frame; dropped, as the gripper '
                     'drops them' % len(frame))
            return b''
        query = self.query_class()
        try:
            slave, pdu = query.parse_request(frame)
        except Exception as exc:  # modbus_tk's invalid-request error: the frame is not a Modbus RTU frame
            self.log('2F-140 Modbus RTU: a frame the gripper cannot read (%s): %s; no reply, as the gripper gives '
                     'none' % (exc, frame[:16].hex(' ')))
            return b''
        if slave != self.slave_id:
            self.log('2F-140 Modbus RTU: a frame for slave %d, not the gripper\'s %d; no reply'
                     % (slave, self.slave_id))
            return b''
        if not pdu:
            self.log('2F-140 Modbus RTU: a frame with no function code; no reply')
            return b''
        response, problem = self.protocol.reply(pdu)
        if problem is not None:
            self.log('2F-140 Modbus RTU: %s; exception %d replied' % (problem, response[1]))
        return query.build_response(response)


def serve_rtu(table, gripper, lock, log, link=None):
    """The gripper on a pseudo-terminal, serving in a thread of its own; the PseudoTerminal."""
    return PseudoTerminal(RtuDevice(table, gripper, lock, log), table['rtu']['frame_gap'], link,
                          "the 2F-140's").start('2F-140 Modbus RTU')


def serve_tcp(table, gripper, lock, log, address, port=None):
    """The gripper behind a Modbus TCP gateway at (address, port), serving in threads of its own; the
    listen.ThreadingServer (shutdown() to end); listen.ListenError (one line) when it cannot listen."""
    protocol = ModbusGripper(table, gripper, lock, 'tcp')
    query_class = framings()[1]

    class Session(socketserver.BaseRequestHandler):
        def handle(self):
            client = '%s:%d' % self.client_address[:2]
            while True:
                header = _receive(self.request, 7)
                if header is None:
                    return
                length = struct.unpack('>H', header[4:6])[0]
                if not 2 <= length <= MAX_ADU - 6:
                    log('2F-140 Modbus TCP: %s sent a header of length %d, not a Modbus frame: its connection is '
                        'closed' % (client, length))
                    return
                body = _receive(self.request, length - 1)
                if body is None:
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
                self.request.sendall(query.build_response(response))

    server = listen.serve('2F-140 Modbus TCP', address, table['tcp']['port'] if port is None else port, Session, log)
    threading.Thread(target=server.serve_forever, name='2F-140 Modbus TCP', daemon=True).start()
    return server


def _receive(sock, size):
    data = b''
    while len(data) < size:
        chunk = sock.recv(size - len(data))
        if not chunk:
            return None
        data += chunk
    return data
