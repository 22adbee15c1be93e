"""Modbus RTU frames as the tests' clients write and check them, from the Modbus over serial line
specification (V1.02, section 2.5.1.2 and appendix B): the CRC-16 with the reflected polynomial 0xA001 from
0xFFFF, least significant byte first. Written here, not taken from the library the devices frame with, so
that a framing error on their side shows."""
import struct


def crc16(data):
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def crc_framed(frame):
    """`frame` with its CRC appended."""
    return frame + struct.pack('<H', crc16(frame))


def valid_crc(frame):
    """Whether the last two bytes of `frame` are the CRC of the rest."""
    return len(frame) >= 3 and crc16(frame[:-2]) == struct.unpack('<H', frame[-2:])[0]


# How long a test watches a line to call it silent (s). A reply it waits for gets REPLY_WAIT: a busy machine
# delays it, never the other way round.
SILENCE, REPLY_WAIT = 0.3, 5.0
# The pause that ends a reply (s): a device writes its reply at once.
PAUSE = 0.05


def exchange(port, frame, wait=REPLY_WAIT):
    """Write `frame` as it is on `port` (an open or closed pyserial port, e.g. a minimalmodbus Instrument's);
    what comes back: the first byte within `wait` s, then the rest until a pause of PAUSE s (b'' for
    silence: pass SILENCE where silence is what the test expects)."""
    if not port.is_open:
        port.open()
    port.reset_input_buffer()
    port.write(frame)
    timeout = port.timeout
    try:
        port.timeout = wait
        reply = port.read(1)
        port.timeout = PAUSE
        while reply:
            more = port.read(256)
            if not more:
                break
            reply += more
        return reply
    finally:
        port.timeout = timeout


class LineClient(object):
    """minimalmodbus (PyPI) on a device's serial line at `path`, opened with the device's `serial` settings
    (baudrate, bytesize, parity, stopbits) as slave `slave_id`; `line` (the device's PseudoTerminal) is shut
    down with it."""

    def __init__(self, path, slave_id, serial, line):
        import minimalmodbus
        self.line = line
        self.client = minimalmodbus.Instrument(path, slave_id, mode=minimalmodbus.MODE_RTU)
        for name, value in serial.items():
            setattr(self.client.serial, name, value)
        self.client.serial.timeout = 2.0  # a reply on a busy machine; an awaited silence costs this much
        self.client.clear_buffers_before_each_transaction = True

    def raw(self, frame, wait=REPLY_WAIT):
        return exchange(self.client.serial, frame, wait)

    def close(self):
        self.client.serial.close()
        self.line.shutdown()
        self.line.close()


def garbage(seed, count, slave_id):
    """`count` seeded frames of 1 to 39 random bytes, half of them with the slave id and a valid CRC (so
    that they reach the device's function codes), as a line with noise or a buggy client delivers them."""
    import random
    rng = random.Random(seed)
    for _ in range(count):
        frame = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 40)))
        yield crc_framed(bytes([slave_id]) + frame) if rng.random() < 0.5 else frame
