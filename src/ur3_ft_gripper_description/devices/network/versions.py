"""Which of a table's fields a controller has: by generation and software version, as UR's documents say."""


def _version(text):
    return None if text is None else tuple(int(part) for part in str(text).split('.'))


def available(entry, generation, version):
    """Whether a field `entry` (its `cb3` / `e_series` first version, its `removed` one) exists on a
    controller of `generation` ('cb3' or 'e_series') at software `version` (a tuple)."""
    first = _version(entry.get(generation))
    removed = _version(entry.get('removed'))
    return first is not None and version[:len(first)] >= first and (removed is None or version < removed)
