"""What the Robotiq devices on the wire share; no ROS.

- RegisterDevice: a Modbus slave's application layer, one request PDU to one response PDU, by the
  function codes of a device's table; a device says which registers it has.
- RtuSlave: Modbus RTU frames in and out for one slave id, through the framing library (modbus_tk).
- PseudoTerminal: the line. A client opens its path (or a symbolic link to it) as it opens a USB
  adapter's serial port. What arrives before a pause goes to the device whole (`device.answer(bytes) ->
  reply bytes`), as a Modbus RTU device reads a frame; the device may also send unasked (`send`), as the
  FT 300 streams.
"""

import errno
import os
import select
import struct
import threading
import tty

from . import listen

MAX_ADU = 260  # the longest Modbus frame (TCP: 7 header bytes and a 253-byte PDU)
# What waits for a client that reads slowly (bytes): four wall-clock seconds of the FT 300's stream at ten
# times real time. A client that reads nothing loses what comes beyond, whole writes at a time.
OUTBOX_BYTES = 1 << 16


class ModbusUnavailable(RuntimeError):
    """The framing library is missing: one line with the fix."""


def framings():
    """(RTU query class, TCP query class) from modbus_tk; ModbusUnavailable without it."""
    try:
        from modbus_tk import modbus_rtu, modbus_tcp
    except ImportError:
        raise ModbusUnavailable('the devices on Modbus need modbus_tk, which this Python does not have: '
                                'pip install modbus_tk==1.1.5 (tools/quickstart installs it)') from None
    return modbus_rtu.RtuQuery, modbus_tcp.TcpQuery


class RegisterDevice(object):
    """A Modbus slave's answers to function codes 3, 4, 16 and 23, as far as `table` names them
    (function_codes: {code: name}, exceptions: {name: code}). Subclasses say which registers there are:
    read(address, count) -> the values, or None where no block holds them all; write(address, values) ->
    None once written, or (exception name, the problem in words); outside(what, address, count, writing) ->
    the words for a request outside the registers. `who` names the device in the problems."""

    who = 'the device'

    def __init__(self, table):
        self.codes = {int(code): name for code, name in table['function_codes'].items()}
        self.exceptions = table['exceptions']

    def exception(self, code, name, problem):
        return struct.pack('>BB', code | 0x80, self.exceptions[name]), problem

    def reply(self, pdu):
        """(response PDU, the problem in words or None) for one request PDU."""
        code = pdu[0]
        kind = self.codes.get(code)
        if kind is None:
            return self.exception(code, 'illegal_function', 'function code %d is not one %s answers (%s)'
                                  % (code, self.who, ', '.join(str(c) for c in sorted(self.codes))))
        return getattr(self, '_' + kind)(code, pdu[1:])

    def _read_registers(self, code, body):
        if len(body) != 4:
            return self.exception(code, 'illegal_data_value', 'a read of %d bytes, not 4' % len(body))
        address, count = struct.unpack('>HH', body)
        if not 1 <= count <= 125:
            return self.exception(code, 'illegal_data_value', 'a read of %d registers (1..125)' % count)
        values = self.read(address, count)
        if values is None:
            return self.exception(code, 'illegal_data_address', self.outside('a read of', address, count, False))
        return struct.pack('>BB%dH' % count, code, 2 * count, *values), None

    _read_holding_registers = _read_input_registers = _read_registers

    def _write_multiple_registers(self, code, body):
        if len(body) < 5 or len(body) != 5 + body[4]:
            return self.exception(code, 'illegal_data_value', 'a write whose length does not match its byte count')
        address, count, size = struct.unpack('>HHB', body[:5])
        if not 1 <= count <= 123 or size != 2 * count:
            return self.exception(code, 'illegal_data_value', 'a write of %d registers in %d bytes' % (count, size))
        refused = self.write(address, list(struct.unpack('>%dH' % count, body[5:])))
        if refused is not None:
            return self.exception(code, *refused)
        return struct.pack('>BHH', code, address, count), None

    def _read_write_multiple_registers(self, code, body):
        if len(body) < 9 or len(body) != 9 + body[8]:
            return self.exception(code, 'illegal_data_value', 'a read/write whose length does not match its byte '
                                  'count')
        read_address, read_count, write_address, write_count, size = struct.unpack('>HHHHB', body[:9])
        if not 1 <= read_count <= 125 or not 1 <= write_count <= 121 or size != 2 * write_count:
            return self.exception(code, 'illegal_data_value', 'a read of %d and a write of %d registers in %d bytes'
                                  % (read_count, write_count, size))
        if self.read(read_address, read_count) is None:
            return self.exception(code, 'illegal_data_address', self.outside('a read of', read_address, read_count,
                                                                             False))
        # The write first, then the read (the protocol's order for function 23).
        refused = self.write(write_address, list(struct.unpack('>%dH' % write_count, body[9:])))
        if refused is not None:
            return self.exception(code, *refused)
        values = self.read(read_address, read_count)
        return struct.pack('>BB%dH' % read_count, code, 2 * read_count, *values), None


class RtuSlave(object):
    """`device` (a RegisterDevice) as Modbus RTU slave `slave_id`: answer(frame) -> the response frame, or b''
    (none: a bad CRC, another slave, a broadcast), through modbus_tk's RTU query; each problem one line of
    `log`, led by `name`."""

    def __init__(self, device, slave_id, name, log):
        self.device, self.slave_id, self.name, self.log = device, slave_id, name, log
        self.query_class = framings()[0]

    def answer(self, frame):
        if len(frame) > MAX_ADU:
            self.log('%s: %d bytes without a pause, longer than any frame; dropped, as %s drops them'
                     % (self.name, len(frame), self.device.who))
            return b''
        query = self.query_class()
        try:
            slave, pdu = query.parse_request(frame)
        except Exception as exc:  # modbus_tk's invalid-request error: the frame is not a Modbus RTU frame
            self.log('%s: a frame %s cannot read (%s): %s; no reply, as %s gives none'
                     % (self.name, self.device.who, exc, frame[:16].hex(' '), self.device.who))
            return b''
        if slave != self.slave_id:
            self.log('%s: a frame for slave %d, not %s\'s %d; no reply' % (self.name, slave, self.device.who,
                                                                          self.slave_id))
            return b''
        if not pdu:
            self.log('%s: a frame with no function code; no reply' % self.name)
            return b''
        response, problem = self.device.reply(pdu)
        if problem is not None:
            self.log('%s: %s; exception %d replied' % (self.name, problem, response[1]))
        return query.build_response(response)


class PseudoTerminal(object):
    """A pseudo-terminal whose other end is a device's serial line: a client opens `path` (or `link`, a symbolic
    link to it) as it would the USB adapter's port. start() serves in a thread of its own, shutdown() ends it."""

    def __init__(self, device, frame_gap, link=None, whose='the device\'s'):
        self.device, self.frame_gap = device, frame_gap
        self.thread = None
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)  # no echo or line editing before the client sets the line up itself
        self.path = os.ttyname(self.slave)
        self.link = link
        if link:
            if os.path.lexists(link) and not os.path.islink(link):
                self.close()
                raise listen.ListenError('%s exists and is not a symbolic link: give %s serial port a free path, '
                                         'e.g. /tmp/ttyRobotiq' % (link, whose))
            try:
                if os.path.islink(link):
                    os.unlink(link)
                os.symlink(self.path, link)
            except OSError as exc:
                self.close()
                raise listen.ListenError('cannot make %s a link to %s serial port: %s; give a path in a directory '
                                         'you can write, e.g. /tmp/ttyRobotiq' % (link, whose, exc.strerror or exc)) \
                    from None
        self._stop = os.pipe()
        os.set_blocking(self._stop[1], False)
        self._sending = threading.Lock()  # replies from this thread, a stream from the device's
        self._outbox = bytearray()
        os.set_blocking(self.master, False)

    def start(self, name):
        self.thread = threading.Thread(target=self.serve_forever, name=name, daemon=True)
        self.thread.start()
        return self

    def serve_forever(self):
        frame = b''
        while True:
            with self._sending:
                waiting = bool(self._outbox)
            ready, writable, _ = select.select([self.master, self._stop[0]], [self.master] if waiting else [], [],
                                               self.frame_gap if frame else None)
            if self._stop[0] in ready and b'x' in os.read(self._stop[0], 4096):
                return
            if writable:
                with self._sending:
                    self._flush()
            if self.master in ready:
                try:
                    frame += os.read(self.master, MAX_ADU)
                except OSError as exc:
                    if exc.errno in (errno.EIO, errno.EAGAIN):
                        continue  # no client has the port open, or nothing to read after all
                    raise
                if len(frame) <= MAX_ADU:
                    continue
            elif ready or writable or not frame:
                continue  # woken for what send() left, not by the silence after a frame
            # The silence after a frame, or more bytes than a frame has: the device takes them.
            response, frame = self.device.answer(frame), b''
            if response:
                self.send(response)

    def send(self, data):
        """Write `data` to the client, whole and in order: what the line cannot take now waits (up to
        OUTBOX_BYTES) and goes out as the client reads; beyond that it is dropped whole, as a device on a line
        sends whether or not anybody listens."""
        with self._sending:
            if len(self._outbox) + len(data) <= OUTBOX_BYTES:
                self._outbox += data
            self._flush()
        if self._outbox:
            try:
                os.write(self._stop[1], b'w')  # the serving thread waits for the line to take the rest
            except BlockingIOError:
                pass  # it has been woken already

    def _flush(self):
        try:
            written = os.write(self.master, self._outbox) if self._outbox else 0
        except BlockingIOError:
            return
        del self._outbox[:written]

    def shutdown(self):
        """The serving thread ends, and the link goes: a client can no longer open the port."""
        try:
            os.write(self._stop[1], b'x')
        except BlockingIOError:
            pass  # a pipe full of wake-ups: the thread is not reading, it has ended
        self._unlink()

    def close(self):
        self._unlink()
        if self.thread is not None:
            self.thread.join(5.0)  # shut down first: its select must not see the descriptors go
        for fd in (self.master, self.slave) + getattr(self, '_stop', ()):
            os.close(fd)

    def _unlink(self):
        if self.link and os.path.islink(self.link) and os.readlink(self.link) == self.path:
            os.unlink(self.link)


