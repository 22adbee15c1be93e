"""URScript sent as text to the controller's client interfaces (30001, 30002, 30003); no ROS.

As UR's client interface documents describe it and the drivers send it: a
client writes URScript, ended by a newline. A `def` program, from its `def`
line to the `end` that closes it at the start of a line, replaces the
running program; a `sec` program runs beside it; any other line is a
one-line program of its own. The controller runs each as it arrives.
"""

# Beyond this many bytes without a complete program, the text is not a program a client sends.
MAX_PROGRAM = 1 << 20


class ScriptError(ValueError):
    """Text that is not URScript a client sends: the connection ends, with this one line."""


class ScriptReader(object):
    """Programs out of the bytes a client sends: feed(data) -> the complete programs, in order."""

    def __init__(self):
        self.pending = b''
        self.program = []  # the lines of a def or sec program not yet ended

    def feed(self, data):
        self.pending += data
        if len(self.pending) + sum(len(line) for line in self.program) > MAX_PROGRAM:
            raise ScriptError('over %d bytes of text without a complete program' % MAX_PROGRAM)
        *lines, self.pending = self.pending.split(b'\n')
        programs = []
        for raw in lines:
            try:
                line = raw.decode('utf-8').rstrip('\r')
            except UnicodeDecodeError:
                raise ScriptError('bytes that are not UTF-8 text') from None
            if self.program:
                self.program.append(line)
                if line.rstrip() == 'end':
                    programs.append('\n'.join(self.program) + '\n')
                    self.program = []
            elif line.startswith(('def ', 'sec ')):
                self.program = [line]
            elif line.strip():
                programs.append(line + '\n')
        return programs


def read_programs(sock, client, face, run, log):
    """Run each program `client` sends on `sock` through `run(text)` until it closes; text that is not
    URScript ends the connection with one log line naming the face and the client."""
    reader = ScriptReader()
    while True:
        data = sock.recv(65536)
        if not data:
            return
        try:
            programs = reader.feed(data)
        except ScriptError as error:
            log('%s: %s sent %s: its connection is closed' % (face, client, error))
            return
        for program in programs:
            run(program)


def ignore_input(sock, client, face, writable_port, log):
    """What `client` sends to a read-only port is read and dropped until it closes: the first of it is one
    log line naming the port that would take it."""
    said = False
    while True:
        data = sock.recv(65536)
        if not data:
            return
        if not said:
            said = True
            log('%s: %s sent text; this port is read-only and runs nothing: send programs and commands to port %d'
                % (face, client, writable_port))
