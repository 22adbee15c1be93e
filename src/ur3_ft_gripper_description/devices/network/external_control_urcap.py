"""The External Control URCap's program node, as the robot runs it when external_control.urp plays; no ROS.

On the pendant the URCap asks the driver's script sender for the program when
the program starts: it connects to the installation's Host IP and Custom
port (50002 by default), sends ``request_program`` and a newline, and runs
what comes back. If nobody answers, the program it runs is an error popup
("Receive program failed"). From the URCap's RequestProgram and the client
library's ScriptSender documentation: the sender answers with the whole
program and a newline, and keeps the connection open.
"""

import socket

REQUEST = b'request_program\n'
DEFAULT_PORT = 50002     # the URCap's Custom port
CONNECT_TIMEOUT = 5.0    # s, the URCap's
FIRST_LINE_TIMEOUT = 0.5  # s: the URCap's read timeout for the first line
# After the first line the URCap takes what has already arrived; the simulated one also waits this long
# (s) for the rest, so that a program split over several writes is not cut.
QUIET = 0.1
MOST = 1 << 20           # bytes: the largest program taken (the driver's is about 30 kB)


class RequestError(RuntimeError):
    """No program came: the text of the URCap's popup."""


def request_program(host, port=DEFAULT_PORT):
    """The program text the script sender at `host`:`port` answers, or RequestError."""
    try:
        with socket.create_connection((host, port), timeout=CONNECT_TIMEOUT) as connection:
            connection.sendall(REQUEST)
            connection.settimeout(FIRST_LINE_TIMEOUT)
            received = b''
            while b'\n' not in received:
                chunk = connection.recv(65536)
                if not chunk:
                    break
                received += chunk
            connection.settimeout(QUIET)
            while len(received) < MOST:
                try:
                    chunk = connection.recv(65536)
                except socket.timeout:
                    break
                if not chunk:
                    break
                received += chunk
    except socket.timeout:
        raise RequestError('Timeout while reading requested program from %s:%d' % (host, port)) from None
    except OSError as error:
        raise RequestError('The connection to the remote PC at %s:%d could not be established. Reason: %s'
                           % (host, port, error.strerror or error)) from None
    if not received.strip():
        raise RequestError('Timeout while reading requested program from %s:%d' % (host, port))
    return received.decode('latin-1')
