"""The package's shipped scripts (examples/, tools/) as modules, loaded from their files.

They are programs, not modules of a package: loading one by its path lets a
test drive the very file users run without putting its folder on sys.path,
where its other files could shadow modules of the same name.
"""
import importlib.util
import os
import sys

import rospkg


def script(relative_path):
    """The module of the shipped script at `relative_path` under the package, e.g. 'examples/guarded_touch.py'.

    Loaded once per process: a second call returns the same module.
    """
    name = os.path.splitext(os.path.basename(relative_path))[0]
    if name in sys.modules:
        return sys.modules[name]
    package_dir = rospkg.RosPack().get_path('ur3_ft_gripper_description')
    spec = importlib.util.spec_from_file_location(name, os.path.join(package_dir, relative_path))
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module
