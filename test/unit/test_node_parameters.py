"""Each node's private parameters have one home, its PARAMETERS table, and nothing gets around it.

- the nodes read a private parameter only through sim_params.read, which
  refuses a name the table does not declare: no ``get_param('~...')`` in src/;
- every private parameter the launch and test files set on the package's
  nodes is declared in that node's table (else a user's setting would be
  silently ignored, and missing from doc/node_parameters.md);
- every node of the package the launch and test files start has a table,
  under the name it is started with.
"""
import ast
import glob
import importlib
import importlib.util
import os

import pytest
import yaml
from lxml import etree

from ur3_ft_gripper_description.devices import sim_params
from ur3_ft_gripper_testing.model import PACKAGE, PACKAGE_DIR


def generator():
    spec = importlib.util.spec_from_file_location(
        'generate_references', os.path.join(PACKAGE_DIR, 'tools', 'generate_references.py'))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


GENERATOR = generator()
TABLES = {node: GENERATOR.load_table(where)[0] for node, where in GENERATOR.NODE_PARAMETER_TABLES.items()}
LAUNCH_FILES = sorted(glob.glob(os.path.join(PACKAGE_DIR, 'launch', '**', '*.launch'), recursive=True) +
                      glob.glob(os.path.join(PACKAGE_DIR, 'test', 'rostest', '*.test')))
READERS = ('get_param', 'has_param', 'search_param')


# -- the launch and test files ------------------------------------------------------------------------

def set_names(element):
    """The parameter names a <param> or <rosparam> sets, relative to where it stands; None if unknowable."""
    if element.tag == 'param':
        return [element.get('name')]
    if element.get('command', 'load') != 'load':
        return []
    if element.get('param'):
        return [element.get('param')]
    if element.get('file'):
        return None  # a YAML file's keys: not known without evaluating the launch file
    loaded = yaml.safe_load(element.text or '')
    return sorted(loaded) if isinstance(loaded, dict) else None


def private_parameters(path, tables):
    """([(node, '~name', line)] set as private parameters of the tables' nodes, [problems]) of one file.

    A <param> inside a <node> of this package is that node's; one elsewhere whose
    name runs through a table's node name (``robotiq_ft_sensor/noise_force``,
    in any namespace) is that node's too.
    """
    found, problems = [], []
    where = os.path.relpath(path, PACKAGE_DIR)
    root = etree.parse(path).getroot()
    for element in root.iter('param', 'rosparam'):
        names = set_names(element)
        node = next((a for a in element.iterancestors('node')), None)
        ours = node is not None and node.get('pkg') == PACKAGE
        if names is None:
            if ours:
                problems.append('%s:%d: <rosparam> in node %s loads keys this test cannot read: set them with '
                                '<param> or param=' % (where, element.sourceline, node.get('name')))
            continue
        for name in names:
            if ours:
                if not name.startswith('/'):
                    found.append((node.get('name'), '~' + name.lstrip('~').split('/')[0], element.sourceline))
                continue
            parts = name.strip('/').split('/')
            hits = [i for i, part in enumerate(parts[:-1]) if part in tables]
            if node is None and hits:
                found.append((parts[hits[-1]], '~' + parts[hits[-1] + 1], element.sourceline))
    return found, problems


def undeclared(paths, tables):
    """Lines naming each private parameter set in `paths` that its node's table lacks, and each node of
    the package started under a name no table has."""
    declared = {node: {entry.name for entry in table} for node, table in tables.items()}
    wrong = []
    for path in paths:
        where = os.path.relpath(path, PACKAGE_DIR)
        for node in etree.parse(path).getroot().iter('node'):
            if node.get('pkg') == PACKAGE and node.get('name') not in tables:
                wrong.append('%s:%d: node %s (%s) has no parameter table in NODE_PARAMETER_TABLES'
                             % (where, node.sourceline, node.get('name'), node.get('type')))
        found, problems = private_parameters(path, tables)
        wrong += problems
        wrong += ['%s:%d: %s sets %s, which its PARAMETERS do not declare' % (where, line, node, name)
                  for node, name, line in found if node in declared and name not in declared[node]]
    return wrong


def test_the_launch_and_test_files_are_found_and_set_private_parameters():
    names = {os.path.relpath(p, PACKAGE_DIR) for p in LAUNCH_FILES}
    assert {'launch/sim_devices.launch', 'launch/sim_arm.launch', 'test/rostest/sim_devices.test'} <= names
    found = {os.path.relpath(path, PACKAGE_DIR): {(node, name) for node, name, _ in private_parameters(path, TABLES)[0]}
             for path in LAUNCH_FILES}
    assert ('robotiq_ft_sensor', '~payload_com') in found['launch/sim_devices.launch']  # a <rosparam param=>
    assert ('ur_hardware_interface', '~world_file') in found['launch/sim_arm.launch']
    assert ('gripper_joint_states', '~gpo_open') in found['launch/ur_ft_gripper_bringup.launch']
    # Set from outside the node, by its path.
    assert ('robotiq_ft_sensor', '~noise_force') in found['test/rostest/sim_devices.test']


def test_every_private_parameter_the_launch_files_set_is_declared():
    wrong = undeclared(LAUNCH_FILES, TABLES)
    assert not wrong, '\n'.join(wrong)


def test_an_undeclared_parameter_or_an_unknown_node_is_found(tmp_path):
    launch = tmp_path / 'a.launch'
    launch.write_text(
        '<launch>\n'
        '  <param name="robotiq_ft_sensor/rate_hz" value="1"/>\n'
        '  <group ns="left">\n'
        '    <node name="robotiq2FGripper" pkg="%s" type="gripper_sim">\n'
        '      <param name="rate" value="10"/>\n'
        '      <param name="object_widht" value="0.05"/>\n'
        '      <rosparam>{physics: true, world: x.yaml}</rosparam>\n'
        '    </node>\n'
        '  </group>\n'
        '  <node name="ft" pkg="%s" type="ft300_sim"/>\n'
        '  <node name="robotiq2FGripper" pkg="robotiq_2f_gripper_control" type="Robotiq2FGripperRtuNode.py">\n'
        '    <param name="not_ours" value="1"/>\n'
        '  </node>\n'
        '</launch>\n' % (PACKAGE, PACKAGE))
    assert undeclared([str(launch)], TABLES) == [
        '%s:10: node ft (ft300_sim) has no parameter table in NODE_PARAMETER_TABLES' % os.path.relpath(
            str(launch), PACKAGE_DIR),
    ] + ['%s:%d: %s sets %s, which its PARAMETERS do not declare' % (os.path.relpath(str(launch), PACKAGE_DIR),
                                                                   line, node, name)
         for line, node, name in [(2, 'robotiq_ft_sensor', '~rate_hz'), (6, 'robotiq2FGripper', '~object_widht'),
                                  (7, 'robotiq2FGripper', '~world')]]


# -- the source ---------------------------------------------------------------------------------------

def private_reads(path):
    """[(line, call)] of each get_param/has_param/search_param of a literal '~name' in a Python file."""
    with open(path) as f:
        text = f.read()
    tree = ast.parse(text, path)
    found = []
    for call in ast.walk(tree):
        if not isinstance(call, ast.Call) or not call.args:
            continue
        function = call.func.attr if isinstance(call.func, ast.Attribute) else getattr(call.func, 'id', None)
        first = call.args[0]
        while isinstance(first, ast.BinOp):  # '~' + name
            first = first.left
        if isinstance(first, ast.JoinedStr) and first.values:  # f'~{name}'
            first = first.values[0]
        name = first.value if isinstance(first, ast.Constant) else None
        if function in READERS and isinstance(name, str) and name.startswith('~'):
            found.append((call.lineno, ast.get_source_segment(text, call)))
    return found


def source_files():
    return sorted(glob.glob(os.path.join(PACKAGE_DIR, 'src', PACKAGE, '**', '*.py'), recursive=True))


def test_no_node_reads_a_private_parameter_around_its_table():
    assert len(source_files()) > 30
    found = ['%s:%d: %s: read it with sim_params.read(get_param, PARAMETERS, name), declared in the table'
             % (os.path.relpath(path, PACKAGE_DIR), line, call)
             for path in source_files() for line, call in private_reads(path)]
    assert not found, '\n'.join(found)


def test_a_private_read_around_the_table_is_found(tmp_path):
    code = tmp_path / 'node.py'
    code.write_text("import rospy\n"
                    "rate = rospy.get_param('~rate', 50.0)\n"
                    "width = get_param('~object_width', None)\n"
                    "there = rospy.has_param('~' + 'physics')\n"
                    "name = rospy.search_param(f'~{rate}')\n"
                    "model = rospy.get_param('robot_description')\n")
    assert [line for line, _ in private_reads(str(code))] == [2, 3, 4, 5]


# -- the tables and the reader ------------------------------------------------------------------------

@pytest.mark.parametrize('node', sorted(TABLES))
def test_a_table_declares_each_private_parameter_once_with_its_meaning(node):
    names = [entry.name for entry in TABLES[node]]
    assert len(names) == len(set(names)), names
    for entry in TABLES[node]:
        assert isinstance(entry, sim_params.Param), entry
        assert entry.name.startswith('~') and entry.doc.strip(), entry
        assert entry.check is None or callable(entry.check), entry


GRIPPER = (sim_params.Param('~rate', 50.0, 'status rate (Hz)', sim_params.number(strictly_above=0.0)),
           sim_params.Param('~initial_position', sim_params.StartupDefault('gpo_open'), 'gPO at start'),
           sim_params.DEVICES_FILE)


def test_the_reader_gives_the_tables_default_and_checks_the_value():
    assert sim_params.read(lambda name, default: default, GRIPPER, '~rate') == 50.0
    assert sim_params.read(lambda name, default: '20', GRIPPER, '~rate') == 20.0
    assert sim_params.read(lambda name, default: default, GRIPPER, '~initial_position', default=3) == 3
    assert sim_params.read(lambda name, default: default, GRIPPER, '~devices_file') == \
        os.path.join(PACKAGE_DIR, 'config', 'sim_devices.yaml')
    with pytest.raises(sim_params.ParamError) as error:
        sim_params.read(lambda name, default: 0, GRIPPER, '~rate')
    assert str(error.value) == '~rate=0 must be > 0'


def test_reading_an_undeclared_parameter_is_a_bug_not_bad_input():
    with pytest.raises(sim_params.ParamDeclarationError) as error:
        sim_params.read(lambda name, default: default, GRIPPER, '~object_width')
    assert not isinstance(error.value, sim_params.ParamError)  # the nodes' one-line handler does not hide it
    assert str(error.value) == "~object_width is read but not declared: add a Param for it to the node's PARAMETERS"
    # A default has one home: the table's, or, for one worked out at start-up, the reader's alone.
    with pytest.raises(sim_params.ParamDeclarationError, match="its default is the table's"):
        sim_params.read(lambda name, default: default, GRIPPER, '~rate', default=20.0)
    with pytest.raises(sim_params.ParamDeclarationError, match='needs the value'):
        sim_params.read(lambda name, default: default, GRIPPER, '~initial_position')
