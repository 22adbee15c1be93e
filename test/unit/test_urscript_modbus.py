"""URScript's modbus_* functions against a real Modbus TCP server on loopback, as UR's manuals describe them.

The robot is the client (its MODBUS client I/O); the unit is modbus_tk's TcpServer (PyPI), on a port of
its own (the node's ~script_modbus_port: the robot's 502 needs root). What the program read comes back
through textmsg, in the robot's log; what it wrote, and the function codes of every request, the unit
records. The user manual's function codes: digital input 0x02, digital output 0x01 then 0x05 once set,
register input 0x04, register output 0x03 then 0x06 once set.
"""
import threading
import time

import pytest
from modbus_tk import defines, hooks, modbus_tcp

from ur3_ft_gripper_testing.rostest_helpers import free_port

from test_ur_arm_core import make_core

DT = 0.002
SLAVE = 255  # the robot's default slave address


class Unit(object):
    """A Modbus TCP unit on loopback: slave 255 with eight of each block, and the function codes it was sent."""

    def __init__(self):
        self.port = free_port()
        self.server = modbus_tcp.TcpServer(port=self.port, address='127.0.0.1')
        self.slave = self.server.add_slave(SLAVE)
        for name, kind in (('coils', defines.COILS), ('inputs', defines.DISCRETE_INPUTS),
                           ('holding', defines.HOLDING_REGISTERS), ('input_registers', defines.ANALOG_INPUTS)):
            self.slave.add_block(name, kind, 0, 8)
        self.lock = threading.Lock()
        self.requests = []  # (function code, address)
        hooks.install_hook('modbus.Slave.handle_request', self._record)
        self.server.start()

    def _record(self, args):
        slave, pdu = args
        if slave is self.slave:
            with self.lock:
                self.requests.append((pdu[0], int.from_bytes(pdu[1:3], 'big')))

    def codes(self, address):
        with self.lock:
            return [code for code, at in self.requests if at == address]

    def close(self):
        hooks.uninstall_hook('modbus.Slave.handle_request', self._record)
        self.server.stop()


@pytest.fixture
def unit():
    made = Unit()
    yield made
    made.close()


@pytest.fixture
def arm(configured_model, unit):
    return make_core(configured_model, **{'~script_modbus_port': unit.port})


def run_program(arm, program, seconds=20.0):
    """Run `program` to its end at the wall clock's pace (the unit answers in wall time, as on a network); the
    lines it logged and the messages the core had."""
    logged = len(arm.robot.log)
    arm.script_command(program)
    messages = arm.take_messages()
    cycles, began = 0, time.monotonic()
    while arm.script_running:
        assert cycles * DT < seconds, 'the program did not end within %g s' % seconds
        arm.step(DT)
        messages += arm.take_messages()
        cycles += 1
        time.sleep(max(0.0, began + cycles * DT - time.monotonic()))
    return list(arm.robot.log)[logged:], messages


def test_inputs_read_what_the_unit_holds_with_the_manuals_function_codes(arm, unit):
    unit.slave.set_values('inputs', 1, [1])
    unit.slave.set_values('input_registers', 3, [54321])  # unsigned: above 32767
    log, messages = run_program(arm, '''def read_unit():
  modbus_add_signal("127.0.0.1", 255, 1, 0, "part_present")
  modbus_add_signal("127.0.0.1", 255, 3, 2, "counter")
  sleep(0.5)
  textmsg("part_present ", modbus_get_signal_status("part_present", False))
  textmsg("counter ", modbus_get_signal_status("counter", False))
end''')
    assert 'part_present True' in log and 'counter 54321' in log, (log, messages)
    assert set(unit.codes(1)) == {0x02} and set(unit.codes(3)) == {0x04}
    # 10 Hz unless set: five updates or so in half a second, not one per control cycle.
    assert 2 <= len(unit.codes(3)) <= 8, unit.codes(3)


def test_outputs_read_the_unit_until_set_then_write_it(arm, unit):
    unit.slave.set_values('holding', 5, [7])
    log, messages = run_program(arm, '''def write_unit():
  modbus_add_signal("127.0.0.1", 255, 5, 3, "speed")
  modbus_add_signal("127.0.0.1", 255, 2, 1, "lamp")
  sleep(0.3)
  textmsg("speed before ", modbus_get_signal_status("speed", False))
  modbus_set_output_register("speed", 4321, False)
  modbus_set_output_signal("lamp", True, False)
  sleep(0.3)
end''')
    assert 'speed before 7' in log, (log, messages)
    assert unit.slave.get_values('holding', 5, 1) == (4321,)
    assert unit.slave.get_values('coils', 2, 1) == (1,)
    speed, lamp = unit.codes(5), unit.codes(2)
    assert speed[0] == 0x03 and 0x06 in speed and set(speed[speed.index(0x06):]) == {0x06}, speed
    assert lamp[0] == 0x01 and 0x05 in lamp and set(lamp[lamp.index(0x05):]) == {0x05}, lamp


def test_an_update_frequency_of_zero_reads_only_when_the_program_asks(arm, unit):
    unit.slave.set_values('input_registers', 0, [11])
    log, messages = run_program(arm, '''def on_demand():
  modbus_add_signal("127.0.0.1", 255, 0, 2, "level")
  modbus_set_signal_update_frequency("level", 0)
  sleep(0.3)
  textmsg("level ", modbus_get_signal_status("level", False))
  sleep(0.3)
end''')
    assert 'level 11' in log, (log, messages)
    # At most one update before the frequency was set to 0, and the program's one read.
    assert 1 <= len(unit.codes(0)) <= 2, unit.codes(0)


def test_a_custom_command_reaches_the_unit_as_its_function_code_and_data(arm, unit):
    # The URScript manual's example: function code 6 (Write Single Register) with register 0x0003 and 600.
    log, messages = run_program(arm, 'def custom():\n  modbus_send_custom_command("127.0.0.1", 255, 6, '
                                     '[0, 3, 2, 88])\n  sleep(0.3)\n  textmsg("sent")\nend')
    assert 'sent' in log, (log, messages)
    assert unit.slave.get_values('holding', 3, 1) == (600,)
    assert unit.codes(3) == [0x06]  # once: a command is no signal, nothing polls it


def test_a_custom_command_to_a_unit_that_does_not_answer_is_one_warning(configured_model):
    arm = make_core(configured_model, **{'~script_modbus_port': free_port()})  # nothing listens there
    log, messages = run_program(arm, 'def custom():\n  modbus_send_custom_command("127.0.0.1", 255, 6, '
                                     '[0, 3, 2, 88])\n  sleep(0.5)\nend')
    warnings = [text for level, text in messages if level == 'warn' and 'custom command' in text]
    assert len(warnings) == 1 and 'not sent' in warnings[0], messages


@pytest.mark.parametrize('call, words', [
    ('modbus_send_custom_command("127.0.0.1", 255, 6, [0, 3, 2, 300])', 'data: 300 is not a byte'),
    ('modbus_send_custom_command("127.0.0.1", 255, 200, [0])', 'function_code 200: use a Modbus function code'),
    ('modbus_send_custom_command("192.0.2.7", 255, 6, [0, 3, 2, 88])',
     'modbus_send_custom_command: 192.0.2.7 is beyond this machine'),
    ('modbus_add_signal("127.0.0.1", 255, 0, 4, "x")', 'signal_type 4: use 0 (digital input)'),
    ('modbus_add_signal("192.0.2.7", 255, 0, 2, "x")', 'modbus_add_signal: 192.0.2.7 is beyond this machine'),
    ('modbus_get_signal_status("nothing", False)', 'modbus_get_signal_status: no MODBUS signal named "nothing"'),
    ('modbus_add_signal("127.0.0.1", 255, 0, 2, "x")\n  modbus_set_output_register("x", 1, False)',
     'modbus_set_output_register: x is a register input, not a register output'),
    ('modbus_add_signal("127.0.0.1", 255, 0, 3, "x")\n  modbus_set_output_register("x", 70000, False)',
     '70000 is not a register value'),
    ('modbus_add_signal("127.0.0.1", 255, 0, 2, "x")\n  modbus_set_signal_update_frequency("x", 200)',
     '200 Hz: use 0 to 125'),
])
def test_a_call_the_robot_refuses_stops_the_program_with_its_runtime_error(arm, call, words):
    arm.script_command('def bad():\n  %s\nend' % call)
    for _ in range(5):
        arm.step(DT)
    errors = [text for level, text in arm.take_messages() if level == 'error']
    assert len(errors) == 1 and 'Runtime error' in errors[0] and words in errors[0], errors


def test_a_unit_that_does_not_answer_is_one_warning_and_the_program_goes_on(configured_model):
    arm = make_core(configured_model, **{'~script_modbus_port': free_port()})  # nothing listens there
    log, messages = run_program(arm, '''def no_unit():
  modbus_add_signal("127.0.0.1", 255, 0, 2, "gone")
  sleep(0.5)
  textmsg("gone ", modbus_get_signal_status("gone", False))
end''')
    assert 'gone 0' in log, (log, messages)
    warnings = [text for level, text in messages if level == 'warn' and 'MODBUS signal "gone"' in text]
    assert len(warnings) == 1 and 'no answer' in warnings[0], messages
