"""The robot's Modbus TCP client, as URScript's modbus_* functions drive it.

As UR's user manual describes its MODBUS client I/O: a signal names a unit
(its IP address and a slave address: 255 where a unit ignores it), an address
on it, and
one of four types. The controller polls each signal at its update frequency
(10 Hz unless set, 0 to 125; 0: only when a program reads it), with one
function code per type:
- 0, digital input: Read Discrete Inputs (0x02);
- 1, digital output: Read Coils (0x01) until a program sets it, then Write
  Single Coil (0x05) at each update;
- 2, register input: Read Input Registers (0x04);
- 3, register output: Read Holding Registers (0x03) until a program sets it,
  then Write Single Register (0x06) at each update.
Registers are unsigned 16-bit integers. modbus_send_custom_command sends a
unit a request of the program's own (its function code and data bytes) once,
and, as the URScript manual says, its answer is not received.

The requests go out from a thread of their own, as the robot's Modbus client
runs beside its programs: a control cycle only queues what its signals' update
frequencies make due in the controller's time, and a program reads the value
of the last answer. modbus_tk (PyPI) frames the requests.
"""

import collections
import queue
import socket
import threading

from ...urscript import Blocking, RuntimeFault

PORT = 502  # Modbus TCP's port, which the robot's client always uses
DEFAULT_FREQUENCY = 10.0  # Hz
MAX_FREQUENCY = 125.0
TIMEOUT = 0.5  # s a unit may take to answer
DIGITAL_INPUT, DIGITAL_OUTPUT, REGISTER_INPUT, REGISTER_OUTPUT = range(4)
TYPE_NAMES = ('digital input', 'digital output', 'register input', 'register output')


class Signal(object):
    def __init__(self, ip, slave, address, kind, name):
        self.ip, self.slave, self.address, self.kind, self.name = ip, slave, address, kind, name
        self.frequency = DEFAULT_FREQUENCY
        self.due = 0.0        # controller s until its next update
        self.value = None     # the last answer's value; None before the first
        self.output = None    # what a program set it to (outputs); None: read the unit's
        self.pending = False  # a request of it waits in the queue
        self.answers = 0      # answers so far (a read on demand waits for the next)
        self.error = None     # the last request's failure, None after a success
        self.reported = None  # the failure last reported

    @property
    def digital(self):
        return self.kind in (DIGITAL_INPUT, DIGITAL_OUTPUT)

    def reading(self):
        """What a program reads: the last answer's value; before any, the type's zero."""
        if self.value is None:
            return False if self.digital else 0
        return bool(self.value) if self.digital else int(self.value)


class CustomCommand(object):
    """A request of the program's own: (function code, data bytes) to a unit, sent once."""

    def __init__(self, ip, slave, pdu):
        self.ip, self.slave, self.pdu = ip, slave, pdu
        self.pending = False


class ScriptModbus(object):
    """The signals a program added, polled at their update frequencies in the controller's time.

    `check_reach(function, address)` raises the robot's runtime error where a program may not connect;
    `log(text)` reports a signal's failure once, and its recovery; `port` is the units' port.
    """

    def __init__(self, check_reach, log, port=PORT):
        self.check_reach = check_reach
        self.log = log
        self.port = int(port)
        self.signals = {}
        self.requests = queue.Queue()
        self.thread = None
        self.custom_failures = collections.deque()  # the client's thread's, for cycle() to report

    # -- the functions ----------------------------------------------------------------------------

    def add_signal(self, ip, slave, address, kind, name):
        if kind not in range(4):
            raise RuntimeFault('modbus_add_signal: signal_type %r: use 0 (digital input), 1 (digital output), '
                               '2 (register input) or 3 (register output)' % (kind,))
        if not 0 <= slave <= 255:
            raise RuntimeFault('modbus_add_signal: slave_number %d: use 0 to 255' % slave)
        if not 0 <= address <= 65535:
            raise RuntimeFault('modbus_add_signal: signal_address %d: use 0 to 65535' % address)
        self.check_reach('modbus_add_signal', ip)
        self._start('modbus_add_signal')
        self.signals[name] = Signal(ip, slave, address, kind, name)  # a name already used: the new one

    def send_custom_command(self, ip, slave, function_code, data):
        function = 'modbus_send_custom_command'
        if not 0 <= slave <= 255:
            raise RuntimeFault('%s: slave_number %d: use 0 to 255' % (function, slave))
        if not 1 <= function_code <= 127:
            raise RuntimeFault('%s: function_code %d: use a Modbus function code, 1 to 127' % (function, function_code))
        for byte in data:
            if not 0 <= byte <= 255:
                raise RuntimeFault('%s: data: %d is not a byte (0 to 255)' % (function, byte))
        self.check_reach(function, ip)
        self._start(function)
        command = CustomCommand(ip, slave, bytes([function_code] + list(data)))
        command.pending = True
        self.requests.put(command)

    def _start(self, function):
        """The client's thread, started with the first signal or command."""
        if self.thread is not None:
            return
        try:
            import modbus_tk  # noqa: F401  (the client's thread frames with it)
        except ImportError:
            raise RuntimeFault('%s: the simulated robot\'s MODBUS client needs modbus_tk: '
                               'pip install modbus_tk==1.1.5 (tools/quickstart installs it)' % function) from None
        self.thread = threading.Thread(target=self._serve, name='modbus client', daemon=True)
        self.thread.start()

    def delete_signal(self, name):
        self._signal('modbus_delete_signal', name)
        del self.signals[name]

    def set_update_frequency(self, name, frequency):
        signal = self._signal('modbus_set_signal_update_frequency', name)
        if not 0.0 <= frequency <= MAX_FREQUENCY:
            raise RuntimeFault('modbus_set_signal_update_frequency: %g Hz: use 0 to %g'
                               % (frequency, MAX_FREQUENCY))
        signal.frequency, signal.due = float(frequency), 0.0

    def get_status(self, name):
        """The signal's value; with an update frequency of 0, a Blocking that waits for a read of its own."""
        signal = self._signal('modbus_get_signal_status', name)
        if signal.frequency > 0.0:
            return signal.reading()
        asked = signal.answers
        self._queue(signal)
        blocking = Blocking(None, None)

        def done():  # the next answer, or failure: a failure leaves the last value
            if signal.answers > asked:
                blocking.result = signal.reading()
                return True
            return False
        blocking.done = done
        return blocking

    def set_output(self, function, name, value, kind):
        signal = self._signal(function, name)
        if signal.kind != kind:
            raise RuntimeFault('%s: %s is a %s, not a %s' % (function, name, TYPE_NAMES[signal.kind],
                                                             TYPE_NAMES[kind]))
        signal.output = value
        self._queue(signal)  # at once, and again at each update

    def _signal(self, function, name):
        try:
            return self.signals[name]
        except KeyError:
            raise RuntimeFault('%s: no MODBUS signal named "%s"' % (function, name)) from None

    # -- the control cycle ------------------------------------------------------------------------

    def cycle(self, dt):
        """After a control cycle of `dt` s: queue the updates now due, and report failures and recoveries."""
        while self.custom_failures:
            self.log(self.custom_failures.popleft())
        for signal in list(self.signals.values()):
            if signal.error != signal.reported:
                self.log('MODBUS signal "%s" (%s:%d, slave %d, address %d): %s' % (
                    signal.name, signal.ip, self.port, signal.slave, signal.address,
                    signal.error or 'answers again'))
                signal.reported = signal.error
            if signal.frequency <= 0.0:
                continue
            signal.due -= dt
            if signal.due <= 1e-9:
                signal.due = max(signal.due + 1.0 / signal.frequency, 0.0)
                self._queue(signal)

    def _queue(self, signal):
        if not signal.pending:
            signal.pending = True
            self.requests.put(signal)

    # -- the client's thread ----------------------------------------------------------------------

    def _serve(self):
        from modbus_tk import defines, exceptions, modbus_tcp
        reads = {DIGITAL_INPUT: defines.READ_DISCRETE_INPUTS, DIGITAL_OUTPUT: defines.READ_COILS,
                 REGISTER_INPUT: defines.READ_INPUT_REGISTERS, REGISTER_OUTPUT: defines.READ_HOLDING_REGISTERS}
        writes = {DIGITAL_OUTPUT: defines.WRITE_SINGLE_COIL, REGISTER_OUTPUT: defines.WRITE_SINGLE_REGISTER}
        units = {}
        while True:
            signal = self.requests.get()
            signal.pending = False
            if isinstance(signal, CustomCommand):
                self._send_custom(signal, modbus_tcp)
                continue
            unit = units.get(signal.ip)
            try:
                if unit is None:
                    unit = units[signal.ip] = modbus_tcp.TcpMaster(signal.ip, self.port, TIMEOUT)
                if signal.output is None:
                    value = unit.execute(signal.slave, reads[signal.kind], signal.address, 1)[0]
                else:
                    output = int(bool(signal.output)) if signal.digital else signal.output
                    unit.execute(signal.slave, writes[signal.kind], signal.address, output_value=output)
                    value = output
            except exceptions.ModbusError as exc:
                signal.error = 'the unit answers exception %d' % exc.get_exception_code()
            except Exception as exc:  # no connection, no answer in time, a garbled answer: the thread goes on
                signal.error = 'no answer (%s)' % (str(exc) or type(exc).__name__)
                units.pop(signal.ip, None)
                if unit is not None:
                    unit.close()
            else:
                signal.value, signal.error = value, None
            signal.answers += 1

    def _send_custom(self, command, modbus_tcp):
        """The command framed by modbus_tk (MBAP header and PDU) on a connection of its own; the unit's answer
        is read and dropped within TIMEOUT, as the manual says a program does not receive it."""
        frame = modbus_tcp.TcpQuery().build_request(command.pdu, command.slave)
        try:
            with socket.create_connection((command.ip, self.port), TIMEOUT) as connection:
                connection.sendall(frame)
                try:
                    connection.recv(260)  # a Modbus TCP answer's most
                except socket.timeout:
                    pass
        except OSError as exc:
            self.custom_failures.append('MODBUS custom command to %s:%d, slave %d: not sent (%s)' % (
                command.ip, self.port, command.slave, str(exc) or type(exc).__name__))
