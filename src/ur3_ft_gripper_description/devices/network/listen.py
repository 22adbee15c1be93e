"""Where a network face listens, and the one line a user reads when it cannot.

A face listens on loopback unless the user names another address: the
robot's own port numbers on 127.0.0.1 by default, and other cells on the
same machine on other loopback addresses (127.0.0.2, ...), which Linux
serves without any set-up, as a second robot on the network has its own IP
address.
"""

import errno
import ipaddress
import queue
import select
import socket
import socketserver
import sys
import threading

LOOPBACK = '127.0.0.1'


class ListenError(RuntimeError):
    """A face that cannot listen: one line naming the address, the problem and the fix."""


def checked_address(text):
    """`text` as an IPv4 address string (a host name is refused: the robot's IP is a number)."""
    try:
        return str(ipaddress.IPv4Address(str(text).strip()))
    except ValueError:
        raise ListenError('%r is not an IPv4 address: give the simulated controller one, e.g. %s (this machine '
                          'only) or 127.0.0.2 for a second cell' % (text, LOOPBACK)) from None


def is_loopback(address):
    return ipaddress.IPv4Address(address).is_loopback


# The peer closed (or shut down its sending side): Linux says so at once, even while data it sent before
# still waits to be read; elsewhere only a reset or a full close shows.
HUNG_UP = getattr(select, 'POLLRDHUP', 0) | select.POLLHUP | select.POLLERR


def peer_hung_up(sock):
    """Whether the client at the other end of `sock` has closed its connection, without reading from it: a
    session thread that has not run since the close has not yet ended the session it serves."""
    poller = select.poll()
    try:
        poller.register(sock, HUNG_UP)
    except ValueError:
        return True  # the socket is closed here already
    return any(events & HUNG_UP for _, events in poller.poll(0))


class ThreadingServer(socketserver.ThreadingMixIn, socketserver.TCPServer):
    """A TCP server with a thread per client, which never keeps the process alive on its own.

    A client's session that fails logs one line through `log` and ends that connection alone.
    """

    daemon_threads = True
    allow_reuse_address = True  # a restarted cell takes its ports back at once, as the robot's controller does

    def __init__(self, name, log, server_address, handler):
        self.name, self.log = name, log
        super().__init__(server_address, handler)

    def get_request(self):
        # Replies and packages go out as they are written, not held for the client's acknowledgement of the
        # last (Nagle): a controller's small replies come within its cycle, not 40 ms later.
        request, client_address = super().get_request()
        request.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        # A session waits on its client for as long as the client stays: rospy sets a 60 s default timeout on
        # every socket its process makes, which would drop a client that only reads (RTDE) or idles (dashboard).
        request.settimeout(None)
        return request, client_address

    def handle_error(self, request, client_address):
        error = sys.exc_info()[1]
        if isinstance(error, ConnectionError):
            return  # the client went away mid-reply, as clients do
        self.log('%s: the session of %s:%d failed: %s: %s; its connection is closed'
                 % (self.name, client_address[0], client_address[1], type(error).__name__, error))


class Outbox(object):
    """What a face sends one client, written by a thread of its own, so that the control cycle never waits
    for a client. A client `size` packages behind loses its connection, with `overflow_line` logged once:
    as UR's controller closes the connection of a client that does not read."""

    def __init__(self, sock, size, overflow_line, log):
        self.socket, self.overflow_line, self.log = sock, overflow_line, log
        self.queue = queue.Queue(size)
        self.overflowed = False
        threading.Thread(target=self._write, daemon=True).start()

    def put(self, data):
        try:
            self.queue.put_nowait(data)
        except queue.Full:
            if not self.overflowed:
                self.overflowed = True
                self.log(self.overflow_line)
                self.socket.shutdown(socket.SHUT_RDWR)

    def close(self):
        """The writer ends after what is queued (the session's end)."""
        try:
            self.queue.put_nowait(None)
        except queue.Full:
            pass  # overflowed: the socket is shut down, the writer ends on its error

    def _write(self):
        while True:
            data = self.queue.get()
            if data is None:
                return
            try:
                self.socket.sendall(data)
            except OSError:
                return


class Broadcast(object):
    """The connected clients of a face that sends all of them the same package (each a send(bytes))."""

    def __init__(self, layout):
        self.layout = layout  # .names read each time, .pack(values) -> bytes
        self.lock = threading.Lock()
        self.clients = []

    def add(self, send):
        with self.lock:
            self.clients.append(send)

    def remove(self, send):
        with self.lock:
            self.clients.remove(send)

    def send(self, read):
        """One package of `read(layout.names)` to every client; nothing is read without a client."""
        with self.lock:
            clients = list(self.clients)
        if clients:
            data = self.layout.pack(read(self.layout.names))
            for send in clients:
                send(data)


def serve(name, address, port, handler, log):
    """A ThreadingServer of `handler` at (address, port), bound and listening; ListenError naming `name`."""
    try:
        return ThreadingServer(name, log, (address, port), handler)
    except OSError as exc:
        if exc.errno == errno.EADDRINUSE:
            fix = ('another simulated or real controller has it: give this cell its own address, e.g. '
                   '127.0.0.2 (robot_ip:=, or sim_robot_ip:= in the bring-up)')
        elif exc.errno == errno.EADDRNOTAVAIL:
            fix = 'this machine has no such address: use %s, or one of its own (ip address)' % LOOPBACK
        elif exc.errno == errno.EACCES:
            fix = 'ports under 1024 need privileges'
        else:
            fix = 'check the address'
        raise ListenError('%s cannot listen on %s:%d: %s; %s' % (name, address, port, exc.strerror or exc, fix)) \
            from None
