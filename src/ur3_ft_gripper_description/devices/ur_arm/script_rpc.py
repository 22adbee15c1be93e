"""URScript's remote procedure calls: rpc_factory("xmlrpc", url) and handle.method(...); no ROS.

As the URScript manual's "Remote Procedure Call (RPC)" section and
rpc_factory define them: the robot is an XML-RPC client of the server at the
URL; a call waits, taking the program's time, until the remote function
returns; a function the server does not have stops the program, and so does
a server that is not there. Values travel as UR's XML-RPC example reads and
writes them: a pose as a struct of x, y, z, rx, ry, rz, a list as an array,
bools, ints, floats and strings as themselves.

A call runs in a thread of its own (xmlrpc.client waits for the answer), so
the control cycle, and the program's other threads, go on meanwhile. Each
call opens its own HTTP connection; closeXMLRPCClientConnection() then has
nothing to close and returns at once. Of the manual's two URL forms the
"pstream" one (xmlrpc-c's packet stream, "host:port") has no client in
Python's library, and is refused naming the form to give instead.
"""

import threading
import urllib.parse
import xmlrpc.client

from ...urscript import Blocking, Pose, RuntimeFault, to_str
from ...urscript.values import type_name

RPC_TYPE = 'xmlrpc'
POSE_MEMBERS = ('x', 'y', 'z', 'rx', 'ry', 'rz')
CLOSE_CONNECTION = 'closeXMLRPCClientConnection'


class RpcHandle(object):
    """What rpc_factory gives: the server's URL, whose methods the program calls."""

    def __init__(self, url):
        self.url = url

    def __repr__(self):
        return '<rpc %s>' % self.url


def _to_wire(value, where):
    if isinstance(value, Pose):
        return dict(zip(POSE_MEMBERS, value))
    if isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, list):
        return [_to_wire(v, where) for v in value]
    raise RuntimeFault('Type error: %s: a %s cannot be sent over XML-RPC' % (where, type_name(value)))


def _from_wire(value, where):
    if isinstance(value, dict):
        if sorted(value) != sorted(POSE_MEMBERS):
            raise RuntimeFault('%s: the server answered a struct of %s; a pose is a struct of %s'
                               % (where, ', '.join(sorted(value)) or 'no members', ', '.join(POSE_MEMBERS)))
        return Pose([_number(value[k], where) for k in POSE_MEMBERS])
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, list):
        return [_from_wire(v, where) for v in value]
    raise RuntimeFault('%s: the server answered a %s, which URScript has no type for'
                       % (where, type(value).__name__))


def _number(value, where):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise RuntimeFault('%s: a pose member must be a number, not %s' % (where, type(value).__name__))
    return float(value)


class ScriptRpc(object):
    """rpc_factory and the calls of its handles. `check_reach(host, function)` raises RuntimeFault for a host
    the program may not reach (the sockets' rule: loopback, and what the user allows)."""

    def __init__(self, check_reach):
        self.check_reach = check_reach

    def factory(self, type, url):
        """rpc_factory(type, url): a handle of the server at `url`."""
        if type != RPC_TYPE:
            raise RuntimeFault('rpc_factory: type must be "%s", not %s' % (RPC_TYPE, to_str(type)))
        if not isinstance(url, str):
            raise RuntimeFault('Type error: rpc_factory: url is a string, not %s' % type_name(url))
        parts = urllib.parse.urlsplit(url)
        if parts.scheme != 'http' or not parts.hostname:
            raise RuntimeFault('rpc_factory: "%s" is not an http URL ("http://<address>:<port>/<path>"); '
                               'the pstream form "<address>:<port>" is not offered by the simulated robot' % url)
        self.check_reach(parts.hostname, 'rpc_factory')
        return RpcHandle(url)

    def call(self, handle, method, args):
        """handle.method(*args): a Blocking whose result is the server's answer."""
        if not isinstance(handle, RpcHandle):
            raise RuntimeFault('Type error: a %s has no method %s' % (type_name(handle), method))
        if method == CLOSE_CONNECTION and not args:
            return None
        where = '%s at %s' % (method, handle.url)
        params = [_to_wire(a, where) for a in args]
        outcome = {}

        def remote():
            try:
                proxy = xmlrpc.client.ServerProxy(handle.url, allow_none=True)
                outcome['answer'] = getattr(proxy, method)(*params)
            except xmlrpc.client.Fault as fault:
                outcome['error'] = '%s: the server answered fault %s: %s' % (where, fault.faultCode,
                                                                           fault.faultString)
            except xmlrpc.client.ProtocolError as exc:
                outcome['error'] = '%s: the server answered HTTP %s %s' % (where, exc.errcode, exc.errmsg)
            except (OSError, OverflowError, ValueError, xmlrpc.client.Error) as exc:
                outcome['error'] = '%s: %s' % (where, exc)

        worker = threading.Thread(target=remote, name='rpc ' + method, daemon=True)
        worker.start()
        blocking = Blocking(None)

        def done():
            if worker.is_alive():
                return False
            if 'error' in outcome:
                raise RuntimeFault(outcome['error'])
            blocking.result = _from_wire(outcome['answer'], where)
            return True

        blocking.done = done
        return blocking
