"""The simulated controller's own network interfaces over its core, started together; no ROS.

Which face answers from which part of the core: the Dashboard Server from
the robot's dashboard; RTDE and the real-time interface from rtde_fields
over each cycle's Snapshot (the real-time package is RTDE's fields in UR's
order); programs sent as text run as script_command's do.
Every call into the core goes through `call(method, *args)`, which the host
(the ROS node, or a test) makes hold the core's lock, so the faces and the
ROS interface see one robot; a program is compiled before, outside the lock
(core.compile_program reads nothing a cycle changes). The host calls `after_cycle` after each
control cycle, holding that lock.
"""

import threading

from ..network import dashboard, external_control_urcap, listen, primary, realtime, rtde
from . import rtde_fields
from .script_robot import STEP_TIME

# The robot's port of each face, in the order they are served.
PORTS = {'dashboard': dashboard.PORT, 'primary': primary.PORTS['primary'], 'secondary': primary.PORTS['secondary'],
         'realtime': realtime.PORT, 'rtde': rtde.PORT,
         'primary_read_only': primary.READ_ONLY_PORTS['primary'],
         'secondary_read_only': primary.READ_ONLY_PORTS['secondary'],
         'realtime_read_only': realtime.READ_ONLY_PORT}


# Wall s a command that replies once done waits for the next cycle at most: a cell whose clock stands
# (paused, or stepped by hand) still answers.
DONE_WAIT = 1.0


class CycleCount(object):
    """The control cycles the faces have sent, for a thread that waits for the next."""

    def __init__(self):
        self.count = 0
        self.changed = threading.Condition()

    def tick(self):
        with self.changed:
            self.count += 1
            self.changed.notify_all()

    def wait_past(self, count, timeout):
        with self.changed:
            return self.changed.wait_for(lambda: self.count > count, timeout)


class NetworkFaces(object):
    """The faces of `core` listening on `address` (listen.ListenError, one line, if one cannot)."""

    def __init__(self, address, core, call, log, ports=None, external_control=None):
        """`external_control`: (host, port) of the driver's script sender, which the External Control URCap
        asks for the program when external_control.urp plays; None: no URCap, the simulation stands in for
        the driver's program (the ROS bring-up's own driver face)."""
        ports = dict(PORTS, **(ports or {}))
        software = core.software
        generation = software.table_key
        self.core = core
        self.readers = {}
        table = rtde.read_table(generation, software.version)
        core.rtde_inputs = frozenset(table['inputs'])
        self.rtde = rtde.Exchange(table, software.version,
                                  1.0 / STEP_TIME[software.generation],
                                  lambda values: call(rtde_fields.apply_inputs, core, values), log)
        self.realtime = realtime.Realtime(realtime.Layout(generation, software.version))
        self.primary = primary.Primary(primary.StateLayout(generation, software.version), software.version)
        run = lambda text: call(core.start_program, core.compile_program(text))  # noqa: E731
        self.cycles = CycleCount()

        def ask(command):
            before = core.robot.external_control_running
            return core.dashboard(command), self.cycles.count, core.robot.external_control_running and not before

        def answer(command):
            reply, cycle, external_control_started = call(ask, command)
            if external_control_started and external_control is not None:
                # As the URCap on the pendant: the program is fetched when it starts, outside the control
                # cycle (the controller goes on meanwhile), and runs once fetched.
                try:
                    program = core.compile_program(external_control_urcap.request_program(*external_control))
                except external_control_urcap.RequestError as error:
                    program = str(error)
                call(core.run_external_control, program)
            if dashboard.done_before_reply(command):
                # Done is when the faces have sent the cycle that carries it.
                self.cycles.wait_past(cycle, DONE_WAIT)
            return reply

        self.servers = []
        try:
            self.servers.append(dashboard.serve(address, answer, log, ports['dashboard']))
            for name in ('primary', 'secondary'):
                self.servers.append(primary.serve(name, address, self.primary, run, answer, log, ports[name]))
            self.servers.append(realtime.serve(address, self.realtime, run, log, ports['realtime']))
            self.servers.append(rtde.serve(address, self.rtde, log, ports['rtde']))
            for name in ('primary', 'secondary'):
                self.servers.append(primary.serve(name, address, self.primary, run, answer, log,
                                                  ports[name + '_read_only'], read_only=True))
            self.servers.append(realtime.serve(address, self.realtime, run, log, ports['realtime_read_only'],
                                               read_only=True))
        except listen.ListenError:
            for server in self.servers:
                server.server_close()
            raise
        self.started = False

    def port(self, name):
        """The port the server of `name` (a key of PORTS) listens on."""
        return self.servers[list(PORTS).index(name)].server_address[1]

    def start(self):
        for server in self.servers:
            threading.Thread(target=server.serve_forever, name=server.name, daemon=True).start()
        self.started = True

    def shutdown(self):
        if self.started:
            # Side by side: each server notices within its poll interval, so five take one interval, not five.
            stoppers = [threading.Thread(target=server.shutdown) for server in self.servers]
            for stopper in stoppers:
                stopper.start()
            for stopper in stoppers:
                stopper.join()
        for server in self.servers:
            server.server_close()

    def after_cycle(self, dt, snapshot):
        """The cycle's data to the faces that stream it (the caller holds the core's lock). Each value is
        computed once a cycle, however many faces and clients read it."""
        values = {}

        def read(names):
            missing = [name for name in names if name not in values]
            for name in missing:
                values[name] = self._reader(name)(self.core, snapshot)
            return [values[name] for name in names]

        self.rtde.cycle(read)
        self.realtime.cycle(read)
        self.primary.cycle(dt, read, self.core.take_program_events())
        self.cycles.tick()

    def _reader(self, name):
        reader = self.readers.get(name)
        if reader is None:
            reader = rtde_fields.reader(name)
            if reader is None:  # a field of the guide the twin has no value for (a test keeps this empty)
                zero = rtde.zero(self.rtde.fields['outputs'][name])
                reader = lambda core, snapshot: zero  # noqa: E731
            self.readers[name] = reader
        return reader
