"""The Dashboard Server (TCP 29999): UR's text protocol over the simulated robot; no ROS.

As UR documents it: a client connects and is greeted with
"Connected: Universal Robots Dashboard Server"; each command is one line
ended by a newline, and each gets the robot's reply on one line; "quit" is
answered "Disconnected" and the connection closed. The replies are the
robot's own (robot_state.RobotState.dashboard, through `answer`), so the
ROS services (ur_arm/dashboard.py) and this face give the same answers.

Bad input costs the client its connection, never the robot: a line longer
than any command (MAX_LINE bytes) or bytes that are not text get one log
line naming the client and the problem, and only that connection closes.
"""

import socketserver

from . import listen

PORT = 29999
GREETING = 'Connected: Universal Robots Dashboard Server'
QUIT, QUIT_REPLY = 'quit', 'Disconnected'
# Longer than any command with a program's path (PolyScope's file names are short): beyond it, not a command.
MAX_LINE = 4096
# The commands that reply once they are done, not once asked (UR's Dashboard Server document: CB3 3.3 on,
# and every e-Series): a client that reads the program state after "Stopped" finds the program stopped.
DONE_BEFORE_REPLY = ('play', 'stop', 'pause', 'load')


def done_before_reply(command):
    words = command.split()
    return bool(words) and words[0].lower() in DONE_BEFORE_REPLY


def reply_to(answer, line):
    """(reply text, whether the connection ends) for one received line (bytes, its newline included or not)."""
    command = line.decode('ascii').rstrip('\r\n')
    if command.strip().lower() == QUIT:
        return QUIT_REPLY, True
    return answer(command), False


def serve(address, answer, log, port=PORT):
    """A listening Dashboard Server at (address, port); `answer(command) -> reply` is the robot's, `log(text)` one
    line. The caller runs serve_forever() in a thread and shutdown() at the end (listen.ThreadingServer)."""

    class Session(socketserver.StreamRequestHandler):
        def handle(self):
            client = '%s:%d' % self.client_address[:2]
            self.wfile.write((GREETING + '\n').encode('ascii'))
            while True:
                line = self.rfile.readline(MAX_LINE + 1)
                if not line:
                    return
                if len(line) > MAX_LINE:
                    log('dashboard server: %s sent a line over %d bytes, not a command: its connection is closed'
                        % (client, MAX_LINE))
                    return
                try:
                    reply, end = reply_to(answer, line)
                except UnicodeDecodeError:
                    log('dashboard server: %s sent bytes that are not ASCII text: its connection is closed' % client)
                    return
                self.wfile.write((reply + '\n').encode('ascii', 'replace'))
                if end:
                    return

    return listen.serve('dashboard server', address, port, Session, log)
