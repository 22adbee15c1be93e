"""URScript's sockets: the TCP connections a program opens by name (socket_open, socket_read_*, ...); no ROS.

As the URScript manual defines them. The robot is the client: socket_open
connects to a server, and the program reads and writes through the socket's
name ('socket_0' by default). Reads wait, taking the program's time, until
what they read has come or their timeout has passed; a failed or timed-out
read returns the manual's failure value, it does not stop the program.

The connections are real sockets, without blocking: each control cycle a
waiting call takes what has arrived. A timeout counts the controller's
time, as everything the program does: a cell running faster than real time
(real_time_factor 0) gives a peer on the network less wall time to answer.
"""

import errno
import ipaddress
import math
import socket
import struct

from ...urscript import Blocking, RuntimeFault

OPEN_TIMEOUT = 2.0       # s: socket_open gives up after this (the manual)
READ_TIMEOUT = 2.0       # s: the reads' default timeout, and socket_get_var's (the manual)
MAX_VALUES = 30          # the most numbers one socket_read_* call reads (the manual)
DEFAULT_SOCKET = 'socket_0'


class _Connection(object):
    def __init__(self, sock):
        self.socket = sock
        self.buffer = b''
        self.closed = False  # the peer closed it

    def take(self):
        """What has arrived since the last look (nothing waits)."""
        while not self.closed:
            try:
                data = self.socket.recv(65536)
            except BlockingIOError:
                return
            except OSError:
                self.closed = True
                return
            if not data:
                self.closed = True
                return
            self.buffer += data


class ScriptSockets(object):
    """The robot's named sockets; `clock()` is the controller's time (s). A program reaches this machine's
    loopback, and beyond it only the IPv4 networks in `allowed` (the user's script_socket_hosts): a program
    sent to the simulated robot does not open connections into the user's network unasked."""

    def __init__(self, clock, allowed=()):
        self.clock = clock
        self.allowed = list(allowed)
        self.connections = {}

    def check_reach(self, address, function='socket_open'):
        """RuntimeFault of `function`, naming the address, where the program may not connect; else nothing."""
        try:
            host = ipaddress.ip_address(socket.gethostbyname(str(address)))
        except (OSError, UnicodeError, ValueError):
            return  # a name that does not resolve fails to connect, as on the robot
        if not host.is_loopback and not any(host in network for network in self.allowed):
            raise RuntimeFault('%s: %s is beyond this machine; the simulated robot connects to loopback '
                               'and to the addresses you allow it (script_socket_hosts:=%s)' % (function, address, host))

    def close_all(self):
        for name in list(self.connections):
            self.close(name)

    def close(self, name=DEFAULT_SOCKET):
        connection = self.connections.pop(name, None)
        if connection is not None:
            connection.socket.close()

    def _waiting(self, timeout, attempt, failure):
        """A Blocking that calls attempt() each cycle until it gives a result (not None), or gives `failure`
        once `timeout` s of the controller's time have passed."""
        start = self.clock()
        blocking = Blocking(None, failure)

        def done():
            result = attempt()
            if result is not None:
                blocking.result = result
                return True
            # A timeout of 0 or less waits until the read completes (the manual).
            return 0.0 < timeout <= self.clock() - start + 1e-9

        result = attempt()
        if result is not None:
            blocking.result, blocking.done = result, lambda: True
        else:
            blocking.done = done
        return blocking

    def open(self, address, port, name=DEFAULT_SOCKET):
        """socket_open: True once connected, False if refused or not within OPEN_TIMEOUT."""
        self.check_reach(address)
        self.close(name)
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setblocking(False)
        try:
            code = sock.connect_ex((str(address), int(port)))
        except (OSError, OverflowError, ValueError):
            sock.close()
            return Blocking(lambda: True, False)
        if code not in (0, errno.EINPROGRESS):
            sock.close()
            return Blocking(lambda: True, False)
        state = {}

        def attempt():
            if 'result' in state:
                return state['result']
            error = sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if error not in (0, errno.EINPROGRESS):
                sock.close()
                state['result'] = False
                return False
            try:
                sock.getpeername()
            except OSError:
                return None  # still connecting
            self.connections[name] = _Connection(sock)
            state['result'] = True
            return True

        return self._waiting(OPEN_TIMEOUT, attempt, False)

    def _connection(self, name):
        return self.connections.get(name)

    def send(self, data, name=DEFAULT_SOCKET):
        """True if `data` (bytes) went out on the socket `name`; False if it is not open or was closed."""
        connection = self._connection(name)
        if connection is None or connection.closed:
            return False
        try:
            connection.socket.setblocking(True)
            connection.socket.settimeout(OPEN_TIMEOUT)
            connection.socket.sendall(data)
            return True
        except OSError:
            connection.closed = True
            return False
        finally:
            connection.socket.setblocking(False)

    def read(self, name, parse, timeout, failure):
        """Wait for what `parse(buffer) -> (value, bytes used) or None` finds on the socket `name`."""
        connection = self._connection(name)
        if connection is None:
            return Blocking(lambda: True, failure)

        def attempt():
            connection.take()
            found = parse(connection.buffer)
            if found is None:
                return failure if connection.closed else None
            value, used = found
            connection.buffer = connection.buffer[used:]
            return value

        return self._waiting(timeout, attempt, failure)


# -- what the reads parse ---------------------------------------------------------------------------

def checked_count(number, what):
    if isinstance(number, bool) or not isinstance(number, int) or not 1 <= number <= MAX_VALUES:
        raise RuntimeFault('%s: number must be an integer from 1 to %d, not %r' % (what, MAX_VALUES, number))
    return number


def number_failure(number, value):
    """A numbers read's failure: 0 read, then `value` in each place (-1, or nan for floats)."""
    return [0] + [value] * number


def binary_integers(number):
    def parse(buffer):
        if len(buffer) < 4 * number:
            return None
        return [number] + list(struct.unpack('>%di' % number, buffer[:4 * number])), 4 * number
    return parse


def byte_list(number):
    def parse(buffer):
        if len(buffer) < number:
            return None
        return [number] + list(buffer[:number]), number
    return parse


def line(buffer):
    end = buffer.find(b'\n')
    if end < 0:
        return None
    return buffer[:end].rstrip(b'\r').decode('latin-1'), end + 1


def ascii_floats(number):
    """'(1.0, 2.5, ...)': `number` numbers in parentheses, separated by commas."""
    def parse(buffer):
        start = buffer.find(b'(')
        end = buffer.find(b')', start + 1)
        if start < 0 or end < 0:
            return None
        try:
            values = [float(v) for v in buffer[start + 1:end].decode('latin-1').split(',')]
        except ValueError:
            values = []
        if len(values) != number:
            return number_failure(number, math.nan), end + 1
        return [number] + values, end + 1
    return parse


MAX_STRING = 1024  # socket_read_string's most characters, its prefix and suffix included (the manual)
ESCAPES = {'\\n': '\n', '\\r': '\r', '\\t': '\t'}


def string(prefix, suffix, interpret_escape):
    """socket_read_string: the text after `prefix` (dropped with what comes before it) up to `suffix` (what
    follows it stays for the next read); without a suffix, what has come. The manual: leading spaces of
    both are ignored, and with interpret_escape \\n, \\r and \\t in them are those characters."""
    prefix, suffix = prefix.lstrip(' '), suffix.lstrip(' ')
    if interpret_escape:
        for written, character in ESCAPES.items():
            prefix, suffix = prefix.replace(written, character), suffix.replace(written, character)
    prefix, suffix = prefix.encode('latin-1'), suffix.encode('latin-1')

    def parse(buffer):
        start = buffer.find(prefix) if prefix else 0
        if start < 0 or len(buffer) <= start + len(prefix) and not suffix:
            return None
        start += len(prefix)
        if not suffix:
            return buffer[start:start + MAX_STRING].decode('latin-1'), min(len(buffer), start + MAX_STRING)
        end = buffer.find(suffix, start)
        if end < 0:
            return None
        return buffer[start:end][:MAX_STRING].decode('latin-1'), end + len(suffix)
    return parse


def variable(name):
    """socket_get_var's answer: '<name> <integer>' on a line."""
    def parse(buffer):
        found = line(buffer)
        if found is None:
            return None
        text, used = found
        words = text.split()
        if len(words) == 2 and words[0] == name:
            try:
                return int(words[1]), used
            except ValueError:
                pass
        return 0, used
    return parse
