"""The tests and benchmarks reach their shared helpers as a package, never through sys.path.

ur3_ft_gripper_testing (test/python/ur3_ft_gripper_testing, declared in setup.py) is
relayed into the devel space like the package itself. A folder put on sys.path
by hand instead works only from where it was written for, and its other files
can shadow real modules. Read from the source with ast: nothing is imported.
"""
import ast
import importlib.util
import os

from ur3_ft_gripper_testing.model import PACKAGE_DIR

HELPERS = 'ur3_ft_gripper_testing'
HELPERS_DIR = os.path.join(PACKAGE_DIR, 'test', 'python', HELPERS)
SCANNED = ('test', 'bench')
PATH_METHODS = ('insert', 'append', 'extend')


def python_files(*folders):
    """Every .py file under the package's `folders`, as paths."""
    found = []
    for folder in folders:
        for root, dirs, files in os.walk(os.path.join(PACKAGE_DIR, folder)):
            dirs[:] = sorted(d for d in dirs if d != '__pycache__')
            found += [os.path.join(root, name) for name in sorted(files) if name.endswith('.py')]
    return found


def is_sys_path(node):
    return (isinstance(node, ast.Attribute) and node.attr == 'path' and isinstance(node.value, ast.Name)
            and node.value.id == 'sys')


def sys_path_changes(path):
    """[line] of each change to sys.path in the file: insert/append/extend, assigned, added to, an item set."""
    with open(path) as f:
        tree = ast.parse(f.read(), path)
    lines = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in PATH_METHODS
                and is_sys_path(node.func.value)):
            lines.append(node.lineno)
        elif isinstance(node, (ast.Assign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if is_sys_path(target) or (isinstance(target, ast.Subscript) and is_sys_path(target.value)):
                    lines.append(node.lineno)
    return sorted(lines)


def top_level_imports(path):
    """[(line, module)] of every absolute import in the file, by its first dotted part."""
    with open(path) as f:
        tree = ast.parse(f.read(), path)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name.split('.')[0]) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            found.append((node.lineno, node.module.split('.')[0]))
    return found


def test_no_file_of_the_tests_or_benchmarks_changes_sys_path():
    changes = ['%s:%d' % (os.path.relpath(path, PACKAGE_DIR), line)
               for path in python_files(*SCANNED) for line in sys_path_changes(path)]
    assert not changes, ('sys.path changed in %s: import the shared helpers as %s (setup.py relays it), a '
                         'shipped script with %s.shipped.script' % (', '.join(changes), HELPERS, HELPERS))


def test_the_scan_finds_each_way_of_changing_sys_path(tmp_path):
    planted = tmp_path / 'planted.py'
    planted.write_text('import os\nimport sys\n'
                       "sys.path.insert(0, os.path.join('test', 'rostest'))\n"
                       "sys.path.append('bench')\n"
                       "sys.path[:0] = ['tools']\n"
                       "sys.path += ['examples']\n"
                       "os.path.join('sys', 'path')\n")
    assert sys_path_changes(str(planted)) == [3, 4, 5, 6]


def test_the_helpers_modules_are_imported_through_their_package():
    modules = {name[:-len('.py')] for name in os.listdir(HELPERS_DIR) if name.endswith('.py')} - {'__init__'}
    assert {'rostest_helpers', 'shipped'} <= modules
    bare = ['%s:%d imports %s' % (os.path.relpath(path, PACKAGE_DIR), line, module)
            for path in python_files(*SCANNED) for line, module in top_level_imports(path) if module in modules]
    assert not bare, 'import these as %s.<module>: %s' % (HELPERS, ', '.join(bare))


def test_no_file_imports_a_rostest_node_as_a_module():
    # Only a sys.path insert made them importable; what they share belongs in the helpers' package.
    nodes = {name[:-len('.py')] for name in os.listdir(os.path.join(PACKAGE_DIR, 'test', 'rostest'))
             if name.endswith('.py')}
    assert 'ur_driver_sim_check' in nodes
    found = ['%s:%d imports %s' % (os.path.relpath(path, PACKAGE_DIR), line, module)
             for path in python_files(*SCANNED) for line, module in top_level_imports(path) if module in nodes]
    assert not found, 'move what these use into %s: %s' % (HELPERS, ', '.join(found))


def test_the_helpers_package_resolves_to_its_folder_in_the_source():
    # find_spec imports the package (the devel space's relay) but not the module.
    spec = importlib.util.find_spec(HELPERS + '.rostest_helpers')
    assert spec is not None, '%s is not importable: build the workspace (setup.py declares it)' % HELPERS
    assert os.path.realpath(spec.origin) == os.path.realpath(os.path.join(HELPERS_DIR, 'rostest_helpers.py'))
