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
        self._sending = threading.Lock()  # replies from this thread, a stream from the device's
        os.set_blocking(self.master, False)

    def start(self, name):
        self.thread = threading.Thread(target=self.serve_forever, name=name, daemon=True)
        self.thread.start()
        return self

    def serve_forever(self):
        frame = b''
        while True:
            ready, _, _ = select.select([self.master, self._stop[0]], [], [], self.frame_gap if frame else None)
            if self._stop[0] in ready:
                return
            if self.master in ready:
                try:
                    frame += os.read(self.master, MAX_ADU)
                except OSError as exc:
                    if exc.errno in (errno.EIO, errno.EAGAIN):
                        continue  # no client has the port open, or nothing to read after all
                    raise
                if len(frame) <= MAX_ADU:
                    continue
            # The silence after a frame, or more bytes than a frame has: the device takes them.
            response, frame = self.device.answer(frame), b''
            if response:
                self.send(response)

    def send(self, data):
        """Write `data` to the client, whole; dropped when the client has not read what came before (a device
        on a line sends whether or not anybody listens)."""
        with self._sending:
            try:
                os.write(self.master, data)
            except BlockingIOError:
                pass

    def shutdown(self):
        """The serving thread ends, and the link goes: a client can no longer open the port."""
        os.write(self._stop[1], b'x')
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


