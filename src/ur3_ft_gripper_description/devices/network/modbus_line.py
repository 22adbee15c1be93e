"""A Modbus RTU line on a pseudo-terminal, and the framing library: what the devices on the wire share; no ROS.

A client opens the pseudo-terminal's path (or a symbolic link to it) as it opens a USB adapter's serial
port. What arrives before a pause goes to the device whole (`device.answer(bytes) -> reply bytes`), as a
Modbus RTU device reads a frame; the device may also send unasked (`send`), as the FT 300 streams.
"""

import errno
import os
import select
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


