"""The External Control URCap's way of starting the driver's program on the simulated controller, on real sockets.

As on the pendant: the dashboard's `load external_control.urp` and `play` make the URCap ask the driver's
script sender for the program (`request_program`, from the client library's ScriptSender documentation),
and the program it answers runs and connects back to the driver. The program is the suite's own
reverse-interface program (test/data/urscript/real/reverse_interface.script); the driver's side is the
test's, written from the client library's documentation. The controller runs in this process, on the wall
clock as ur_controller_sim runs it.
"""
import contextlib
import random
import socket
import threading
import time

import numpy as np
import pytest

from ur3_ft_gripper_description.devices.ur_arm import controller_sim
from test_network_dashboard import Client as DashboardClient
from test_urscript_real_programs import SERVOJ, Driver, driver_filled, motion, program

WAIT = 30.0  # wall s for the other side (the controller's thread, the URCap's request) to act


class ScriptSender(object):
    """The driver's script sender: answers each "request_program\\n" with the program and a newline, and
    keeps the connection open."""

    def __init__(self, text):
        self.text = text
        self.listener = socket.socket()
        self.listener.bind(('127.0.0.1', 0))
        self.listener.listen(4)
        self.port = self.listener.getsockname()[1]
        self.requests = []
        self.connections = []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        while True:
            try:
                connection, _ = self.listener.accept()
            except OSError:
                return
            self.connections.append(connection)
            received = b''
            while not received.endswith(b'\n'):
                chunk = connection.recv(4096)
                if not chunk:
                    break
                received += chunk
            self.requests.append(received)
            if received == b'request_program\n':
                connection.sendall((self.text + '\n').encode())

    def close(self):
        for sock in self.connections + [self.listener]:
            sock.close()


def wait_for(condition, what):
    deadline = time.monotonic() + WAIT
    while not condition():
        assert time.monotonic() < deadline, 'timed out waiting for %s' % what
        time.sleep(0.01)


@contextlib.contextmanager
def controller(external_control):
    """(core, lock, dashboard client) of a ur5e controller on a loopback address of its own, stepped on the wall
    clock as ur_controller_sim steps it, its URCap pointing at `external_control` (host, port)."""
    address = '127.%d.%d.%d' % (random.randint(1, 254), random.randint(0, 254), random.randint(2, 254))
    core, faces, lock = controller_sim.build('ur5e', address, external_control=external_control,
                                             log=lambda text: None)
    stop = threading.Event()
    faces.start()
    runner = threading.Thread(target=controller_sim.run, args=(core, faces, lock, stop), daemon=True)
    runner.start()
    dashboard = DashboardClient(29999, address)
    try:
        yield core, lock, dashboard
    finally:
        dashboard.close()
        stop.set()
        runner.join()
        faces.shutdown()


@pytest.fixture
def cell():
    """(core, lock, dashboard client, driver, sender): the controller's URCap points at the test's script
    sender, which serves the reverse-interface program filled for the test's driver."""
    driver = Driver()
    sender = ScriptSender(driver_filled(program('reverse_interface.script'), driver))
    try:
        with controller(('127.0.0.1', sender.port)) as (core, lock, dashboard):
            yield core, lock, dashboard, driver, sender
    finally:
        driver.close()
        sender.close()


def test_play_fetches_the_drivers_program_which_follows_the_driver_until_its_keepalive_stops(cell):
    core, lock, dashboard, driver, sender = cell
    assert dashboard.ask('load external_control.urp') == 'Loading program: external_control.urp'
    with lock:
        start = core.actual_state()[0]
    assert dashboard.ask('play') == 'Starting program'
    assert sender.requests == [b'request_program\n']
    wait_for(driver.connected, "the program's connections to the driver")
    assert dashboard.ask('programState') == 'PLAYING external_control.urp'
    # The driver streams servoj targets as it runs, here at 250 Hz of the wall clock, with a generous
    # receive timeout: a busy machine's stalls are not the keepalive stopping.
    target = start + [0.1, 0.0, 0.0, 0.0, 0.0, -0.1]
    began = time.monotonic()
    while True:
        elapsed = time.monotonic() - began
        driver.reverse.connection.sendall(motion(start + (target - start) * min(elapsed, 1.0), SERVOJ,
                                                 timeout_ms=1000))
        with lock:
            position = core.actual_state()[0]
        if elapsed > 1.0 and np.allclose(position, target, atol=1e-4):
            break
        assert elapsed < WAIT, 'the arm did not reach the target: %s' % (position - start)
        time.sleep(0.004)
    # The driver goes quiet: the program stops the arm and ends, and the robot reports it stopped.
    wait_for(lambda: dashboard.ask('programState') == 'STOPPED external_control.urp', 'the program to end')
    with lock:
        log = list(core.robot.log)
        assert np.allclose(core.actual_state()[0], target, atol=1e-4)
    assert log[-2] == 'reverse_socket: nothing within 1' and log[-1].startswith('commands followed ')


def test_play_without_a_script_sender_shows_the_urcaps_popup_and_stops():
    with socket.socket() as unused:
        unused.bind(('127.0.0.1', 0))
        port = unused.getsockname()[1]  # nobody listens there once it is closed
    with controller(('127.0.0.1', port)) as (core, lock, dashboard):
        assert dashboard.ask('play') == 'Starting program'
        assert dashboard.ask('programState') == 'STOPPED external_control.urp'
        with lock:
            popup, log = core.robot.popup, list(core.robot.log)
    assert popup.startswith('The connection to the remote PC at 127.0.0.1:%d could not be established' % port), popup
    assert log[-1] == popup
