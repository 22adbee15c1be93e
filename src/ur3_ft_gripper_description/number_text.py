"""Numbers written into text that something reads back: world files, URScript, XML, YAML.

numpy 2 writes a numpy scalar's repr as `np.float64(0.29)`, and so do %r, and
str() or %s of a list or tuple holding one: a word to a YAML, URScript or XML
reader, not a number. These write Python's float instead, whatever type holds
the value, the same under numpy 1 and 2.
"""


def number(value):
    """`value` (an int, a float or a numpy scalar) as the shortest text that reads back as the same float."""
    return repr(float(value))


def number_list(values, separator=', '):
    """number() of each of `values`, joined by `separator`."""
    return separator.join(number(v) for v in values)
