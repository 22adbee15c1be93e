"""The package's imports run one way: no circle, model/ below devices/, the shared names at the bottom.

Read from the source with ast (nothing is imported): every ``import`` and
``from ... import`` of the package, at module level and inside functions
alike, is an edge from the importing module to the imported one. Imports of
other libraries are not edges; the trimesh check below reads them.
"""
import ast
import os

import pytest

from ur3_ft_gripper_testing.model import PACKAGE, PACKAGE_DIR

SOURCE = os.path.join(PACKAGE_DIR, 'src', PACKAGE)
NAMES = PACKAGE + '.model.names'
EXPANSION = PACKAGE + '.model.description'


def module_files(root=SOURCE):
    """{dotted module name: path} of every .py file of the package (a package is its __init__)."""
    found = {}
    for folder, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d != '__pycache__')
        parts = [PACKAGE] + os.path.relpath(folder, root).split(os.sep)
        parts = [p for p in parts if p != '.']
        for name in sorted(files):
            if name.endswith('.py'):
                stem = name[:-len('.py')]
                found['.'.join(parts if stem == '__init__' else parts + [stem])] = os.path.join(folder, name)
    return found


def imports(path, module, modules):
    """[(imported module, level: 'module' or 'function', line)] of the package, and the other libraries' names."""
    with open(path) as f:
        tree = ast.parse(f.read(), path)
    is_package = path.endswith('__init__.py')
    package_parts = module.split('.') if is_package else module.split('.')[:-1]
    function_lines = {n.lineno for node in ast.walk(tree) if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
                      for n in ast.walk(node) if isinstance(n, (ast.Import, ast.ImportFrom))}
    edges, libraries = [], set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = '.'.join(package_parts[:len(package_parts) - node.level + 1] +
                                ([node.module] if node.module else []))
            else:
                base = node.module
            # `from a import b`: the module a.b when there is one, else a's name b.
            targets = [base + '.' + alias.name if base + '.' + alias.name in modules else base
                       for alias in node.names]
        else:
            continue
        level = 'function' if node.lineno in function_lines else 'module'
        for target in targets:
            if target == PACKAGE or target.startswith(PACKAGE + '.'):
                edges.append((target, level, node.lineno))
            else:
                libraries.add(target.split('.')[0])
    return edges, libraries


def import_graph():
    modules = module_files()
    graph, libraries = {}, {}
    for module, path in modules.items():
        edges, libraries[module] = imports(path, module, modules)
        unknown = [target for target, _, _ in edges if target not in modules]
        assert not unknown, '%s imports %s, which is not a module of the package' % (module, unknown)
        graph[module] = edges
    return graph, libraries


GRAPH, LIBRARIES = import_graph()


def reachable(start):
    seen, todo = set(), [start]
    while todo:
        for target, _, _ in GRAPH[todo.pop()]:
            if target not in seen:
                seen.add(target)
                todo.append(target)
    return seen


def cycle(graph=GRAPH):
    """One circle of imports in `graph` as [module, ..., module] (first == last), or None."""
    state = {}

    def visit(module, path):
        state[module] = 'open'
        for target, _, _ in graph[module]:
            if state.get(target) == 'open':
                return path[path.index(target):] + [target]
            if target not in state:
                found = visit(target, path + [target])
                if found:
                    return found
        state[module] = 'done'
        return None

    for module in sorted(graph):
        if module not in state:
            found = visit(module, [module])
            if found:
                return found
    return None


def test_the_graph_sees_the_package_and_both_kinds_of_import():
    assert {EXPANSION, PACKAGE + '.model.inertials', PACKAGE + '.devices.ur_arm.arm_sim'} <= set(GRAPH)
    levels = {level for edges in GRAPH.values() for _, level, _ in edges}
    assert levels == {'module', 'function'}  # cli imports export and mjcf on demand
    # A relative import resolves: ur_arm's `from .. import sim_params`.
    assert PACKAGE + '.devices.sim_params' in {t for t, _, _ in GRAPH[PACKAGE + '.devices.ur_arm.settings']}


def test_a_circle_through_a_function_level_import_is_found():
    graph = {'a': [('b', 'module', 1)], 'b': [('c', 'module', 1)], 'c': [('a', 'function', 9)], 'd': [('a', 'module', 1)]}
    assert cycle(graph) == ['a', 'b', 'c', 'a']
    graph['c'] = []
    assert cycle(graph) is None


def test_no_import_circle_at_module_or_function_level():
    found = cycle()
    assert found is None, 'the imports go round: %s' % ' -> '.join(found)


def test_the_model_never_imports_the_simulated_devices():
    wrong = ['%s:%d %s (%s level)' % (module, line, target, level)
             for module, edges in sorted(GRAPH.items()) if module.startswith(PACKAGE + '.model')
             for target, level, line in edges if target.startswith(PACKAGE + '.devices')]
    assert not wrong, wrong


def test_the_shared_names_import_nothing_of_the_package():
    assert NAMES in GRAPH, '%s is the bottom module the others take shared names from' % NAMES
    assert GRAPH[NAMES] == []


@pytest.mark.parametrize('module', ['devices.gripper_model', 'devices.gripper_sim', 'devices.gripper_joint_states',
                                    'devices.ft300_sim', 'devices.wrench_model', 'model.tcp', 'model.inertials'])
def test_frame_names_and_the_inertials_do_not_load_the_xacro_engine(module):
    # The devices read robot_description; the TCP works on a URDF text.
    assert EXPANSION not in reachable(PACKAGE + '.' + module)


def test_expanding_the_model_never_needs_trimesh():
    # trimesh makes config/link_inertials.yaml; expansion only reads it.
    needs = sorted(m for m in reachable(EXPANSION) | {EXPANSION} if 'trimesh' in LIBRARIES[m])
    assert not needs, needs
