"""YAML documents read with PyYAML's libyaml parser where PyYAML has it (Debian's python3-yaml and PyPI's
wheels do), else with its pure-Python one: the same documents and errors, read five to ten times faster.
Every node's start, every controller and physics cell a test builds, reads the package's tables."""
import yaml

SAFE_LOADER = getattr(yaml, 'CSafeLoader', yaml.SafeLoader)


def load(stream):
    """What safe_load(stream) returns."""
    return yaml.load(stream, Loader=SAFE_LOADER)
