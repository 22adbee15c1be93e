"""URScript's remote procedure calls (rpc_factory and a handle's methods) against a real XML-RPC server.

The server is Python's own, set up as UR's XML-RPC example sets it up
(HTTP/1.1, None allowed); its functions are the peers of each test. What the
program got back comes through textmsg, in the robot's log; what it sent, the
server's functions keep.
"""
import threading
import time
import xmlrpc.server

import pytest

from test_ur_arm_core import make_core
from test_urscript_sockets import run_program

POSE = {'x': 0.1, 'y': -0.2, 'z': 0.3, 'rx': 0.1, 'ry': 3.14, 'rz': -0.2}


class Server(object):
    """An XML-RPC server on loopback in a thread of its own; `calls` lists (function, arguments) received."""

    def __init__(self, **functions):
        self.calls = []
        self.server = xmlrpc.server.SimpleXMLRPCServer(('127.0.0.1', 0), allow_none=True, logRequests=False)
        self.server.RequestHandlerClass.protocol_version = 'HTTP/1.1'
        for name, function in functions.items():
            self.server.register_function(self._recording(name, function), name)
        self.url = 'http://127.0.0.1:%d/RPC2' % self.server.server_address[1]
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def _recording(self, name, function):
        def recorded(*args):
            self.calls.append((name, args))
            return function(*args)
        return recorded

    def close(self):
        self.server.shutdown()
        self.server.server_close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


@pytest.fixture
def arm(configured_model):
    return make_core(configured_model)


def program(text):
    return 'def rpc_program():\n%s\nend\n' % '\n'.join('  ' + line for line in text.strip().split('\n'))


def error_of(arm, text, cycles=2000):
    """The robot's runtime error for `text` (it must stop on one)."""
    arm.script_command(text)
    for _ in range(cycles):
        arm.step(0.002)
        messages = [m for level, m in arm.take_messages() if level == 'error']
        if messages:
            return messages[-1]
        time.sleep(0.001)  # the server's thread answers on the wall clock
    raise AssertionError('the program did not stop on an error')


def test_the_manuals_camera_example_runs_against_a_camera_server(arm):
    with Server(initialize=lambda mode: mode == 'RGB', takeSnapshot=lambda: True, getTarget=lambda: POSE) as server:
        log = run_program(arm, program('''
camera = rpc_factory("xmlrpc", "%s")
if (! camera.initialize("RGB")):
  popup("Camera was not initialized")
end
camera.takeSnapshot()
target = camera.getTarget()
camera.closeXMLRPCClientConnection()
textmsg(target)
''' % server.url))
    assert server.calls == [('initialize', ('RGB',)), ('takeSnapshot', ()), ('getTarget', ())]
    assert log == ['p[0.1, -0.2, 0.3, 0.1, 3.14, -0.2]']


def test_a_pose_travels_as_urs_example_reads_it_a_struct_of_x_y_z_rx_ry_rz(arm):
    def get_next_pose(p):
        assert type(p) is dict
        return dict(p, z=p['z'] + 0.05)
    with Server(get_next_pose=get_next_pose) as server:
        log = run_program(arm, program('''
camera = rpc_factory("xmlrpc", "%s")
next_pose = camera.get_next_pose(p[0.4, -0.1, 0.2, 0.05, 3.14159, -0.3])
textmsg(next_pose)
''' % server.url))
    assert server.calls == [('get_next_pose', ({'x': 0.4, 'y': -0.1, 'z': 0.2, 'rx': 0.05, 'ry': 3.14159,
                                                 'rz': -0.3},))]
    assert log == ['p[0.4, -0.1, 0.25, 0.05, 3.14159, -0.3]']


def test_bools_ints_floats_strings_and_lists_arrive_as_themselves_and_come_back(arm):
    with Server(echo=lambda *args: list(args)) as server:
        log = run_program(arm, program('''
rpc = rpc_factory("xmlrpc", "%s")
textmsg(rpc.echo(True, 12, 12.5, "Hello", [12, 1.5, 123], [[1, 2], [3, 4]]))
''' % server.url))
    received = server.calls[0][1]
    assert received == (True, 12, 12.5, 'Hello', [12, 1.5, 123], [[1, 2], [3, 4]])
    assert [type(v) for v in received[:4]] == [bool, int, float, str]
    assert log == ['[True, 12, 12.5, Hello, [12, 1.5, 123], [[1, 2], [3, 4]]]']


def test_the_control_cycle_and_the_programs_threads_go_on_while_the_server_works(arm):
    with Server(slow=lambda: time.sleep(1.0) or 'done') as server:
        log = run_program(arm, program('''
global cycles = 0
thread count():
  while True:
    cycles = cycles + 1
    sync()
  end
end
counter = run count()
rpc = rpc_factory("xmlrpc", "%s")
answer = rpc.slow()
kill counter
textmsg(answer, cycles)
''' % server.url))
    answer, cycles = log[0][:4], int(log[0][4:])
    # 1 s of the server's work is 500 control cycles of 2 ms, paced to the wall clock; a call that held
    # the cycle would leave one or two. 100 leaves room for a busy machine.
    assert answer == 'done' and cycles >= 100


def test_a_function_the_server_does_not_have_stops_the_program_naming_it(arm):
    with Server(initialize=lambda mode: True) as server:
        text = error_of(arm, program('camera = rpc_factory("xmlrpc", "%s")\ncamera.calibrate(3)' % server.url))
    assert text.startswith('script_command: RuntimeException: Runtime error in line 3, column 3 Error: '
                           'calibrate at %s: the server answered fault 1: ' % server.url)
    assert 'calibrate' in text.split('fault 1: ')[1] and text.endswith('; program stopped')


def test_no_server_at_the_url_stops_the_program_naming_it(arm):
    idle = Server()
    url = idle.url
    idle.close()
    text = error_of(arm, program('camera = rpc_factory("xmlrpc", "%s")\ncamera.initialize("RGB")' % url))
    assert text.startswith('script_command: RuntimeException: Runtime error in line 3, column 3 Error: '
                           'initialize at %s: ' % url)
    assert 'refused' in text


@pytest.mark.parametrize('arguments, error', [
    ('"xmlrpc", "http://192.0.2.7:50000/RPC2"',
     'rpc_factory: 192.0.2.7 is beyond this machine; the simulated robot connects to loopback and to the '
     'addresses you allow it (script_socket_hosts:=192.0.2.7)'),
    ('"xmlrpc", "127.0.0.1:50000"',
     'rpc_factory: "127.0.0.1:50000" is not an http URL ("http://<address>:<port>/<path>"); the pstream form '
     '"<address>:<port>" is not offered by the simulated robot'),
    ('"json", "http://127.0.0.1:50000/RPC2"', 'rpc_factory: type must be "xmlrpc", not json'),
])
def test_a_url_the_robot_may_not_use_is_the_robots_runtime_error_at_rpc_factory(arm, arguments, error):
    text = error_of(arm, program('camera = rpc_factory(%s)' % arguments))
    assert text == ('script_command: RuntimeException: Runtime error in line 2, column 12 Error: %s; '
                    'program stopped' % error)


def test_a_struct_that_is_not_a_pose_stops_the_program_naming_its_members(arm):
    with Server(status=lambda: {'ok': True}) as server:
        text = error_of(arm, program('rpc = rpc_factory("xmlrpc", "%s")\nx = rpc.status()' % server.url))
    assert text.endswith('Error: status at %s: the server answered a struct of ok; a pose is a struct of '
                         'x, y, z, rx, ry, rz; program stopped' % server.url)


def test_a_method_of_something_else_than_a_handle_stops_the_program(arm):
    text = error_of(arm, program('x = 3\nx.initialize("RGB")'))
    assert text.endswith('Error: Type error: a int has no method initialize; program stopped')


def test_a_secondary_program_may_not_wait_for_a_server():
    from ur3_ft_gripper_description.urscript import CompileError, compile_script
    with pytest.raises(CompileError) as caught:
        compile_script('sec ask():\n  rpc = rpc_factory("xmlrpc", "http://127.0.0.1:50000/RPC2")\n  rpc.get()\nend\n',
                       {'rpc_factory': False})
    assert (caught.value.line, str(caught.value).split(': ', 1)[1]) == (
        3, 'a secondary program may not use physical time: get')
