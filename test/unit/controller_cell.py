"""The simulated controller's core with its network faces on free loopback ports, without ROS, for the
tests of the faces: stepped as the arm's node steps it, each face seeing every cycle."""
import threading
import time

from ur3_ft_gripper_description.devices.network import listen
from ur3_ft_gripper_description.devices.ur_arm.network_faces import PORTS, NetworkFaces
from ur3_ft_gripper_testing.rtde_client import RtdeClient
from test_ur_arm_core import make_core

TAKE_IN = 30.0  # wall s for a face's thread to take a connection or its text in


class Cell(object):
    """A core and its network faces on free loopback ports, stepped as the arm's node steps them."""

    def __init__(self, configured_model, ur_type):
        self.core, self.lock, self.logged = make_core(configured_model, ur_type), threading.RLock(), []
        self.dt = 1.0 / rtde_max_frequency(self.core)
        self.calls = []  # (method name, arguments) of each call the faces made under the core's lock

        def call(method, *args):
            with self.lock:
                self.calls.append((method.__name__, args))
                return method(*args)

        self.faces = NetworkFaces(listen.LOOPBACK, self.core, call, self.logged.append,
                                  ports={name: 0 for name in PORTS})
        self.faces.start()
        self.port = self.faces.port('rtde')

    def step(self, cycles=1):
        for _ in range(cycles):
            with self.lock:
                snapshot = self.core.step(self.dt)
                self.faces.after_cycle(self.dt, snapshot)

    def step_until(self, condition, what, seconds=TAKE_IN):
        """Step the cell until condition() holds after a cycle, for what the faces' threads take in: within
        `seconds` of the wall clock. Each cycle also waits its period on the wall clock, so that the
        controller's clock keeps to the faces' threads: on a busy machine a face's thread may wait long for
        the interpreter, and a clock running flat out meanwhile would put a client the test is not reading
        its face's whole queue behind, and the face closes such a client's connection, as the robot does."""
        deadline = time.monotonic() + seconds
        while not condition():
            assert time.monotonic() < deadline, '%s did not happen within %g s' % (what, seconds)
            self.step()
            time.sleep(self.dt)

    def client(self, protocol=2):
        client = RtdeClient(self.port)
        assert client.negotiate(protocol)
        return client


def rtde_max_frequency(core):
    return 125.0 if core.software.generation == 'CB3' else 500.0

