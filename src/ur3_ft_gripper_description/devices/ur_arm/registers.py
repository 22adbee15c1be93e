"""The controller's general purpose registers, which programs and RTDE clients share; no ROS.

As the URScript manual and the RTDE guide number them: 128 boolean, 48
integer and 48 float registers each way. Input registers are written by
the outside (RTDE clients, fieldbus) and read by programs; output
registers are written by programs and read by the outside. The lower 64
boolean registers are the fieldbus's, the upper 64 RTDE's, but both read
and write alike here, as nothing but RTDE reaches them.
"""

BOOLEAN, INTEGER, FLOAT = 'boolean', 'integer', 'float'
COUNT = {BOOLEAN: 128, INTEGER: 48, FLOAT: 48}
INT32 = (-2 ** 31, 2 ** 31 - 1)
ZERO = {BOOLEAN: False, INTEGER: 0, FLOAT: 0.0}


class RegisterError(ValueError):
    """An address or a value the registers do not take; one line naming it."""


class Registers(object):
    """`input[kind][address]` and `output[kind][address]`, kind one of BOOLEAN, INTEGER, FLOAT."""

    def __init__(self):
        self.input = {kind: [ZERO[kind]] * count for kind, count in COUNT.items()}
        self.output = {kind: [ZERO[kind]] * count for kind, count in COUNT.items()}

    @staticmethod
    def checked(kind, address, value=None):
        """(address, value) as the registers keep them; RegisterError naming the problem."""
        if isinstance(address, bool) or not isinstance(address, (int, float)) or address != int(address) or \
                not 0 <= int(address) < COUNT[kind]:
            raise RegisterError('%s register %r does not exist (0 to %d)' % (kind, address, COUNT[kind] - 1))
        if value is None:
            return int(address), None
        if kind == BOOLEAN:
            if not isinstance(value, bool):
                raise RegisterError('a boolean register takes True or False, not %r' % (value,))
        elif kind == INTEGER:
            if isinstance(value, bool) or not isinstance(value, int) or not INT32[0] <= value <= INT32[1]:
                raise RegisterError('an integer register takes a 32-bit signed integer, not %r' % (value,))
        else:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise RegisterError('a float register takes a number, not %r' % (value,))
            value = float(value)
        return int(address), value

    def read(self, direction, kind, address):
        return getattr(self, direction)[kind][self.checked(kind, address)[0]]

    def write(self, direction, kind, address, value):
        address, value = self.checked(kind, address, value)
        getattr(self, direction)[kind][address] = value
