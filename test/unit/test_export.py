"""export_urdf: the flattened file, its mesh paths, an independent URDF library, bad options."""
import os

import numpy as np
import pytest
import yaml
import yourdfpy

from ur3_ft_gripper_description.model import export
from ur3_ft_gripper_testing.model import UR_CONFIG_ROOT, ExpandedModel, run_export

CASES = {  # name -> export_urdf options
    'ur3-default': [],
    'ur5e-coupling-prefixed': ['--ur-type', 'ur5e', '--no-ft-sensor', '--prefix', 'r1_'],
    'ur30-sensor-only-world': ['--ur-type', 'ur30', '--no-gripper', '--world'],
    'ur10-bare': ['--ur-type', 'ur10', '--no-ft-sensor', '--no-gripper'],
}


def exported(tmp_path, options, absolute):
    out = tmp_path / 'model.urdf'
    run = run_export(*(options + (['--absolute-meshes'] if absolute else []) + ['-o', str(out)]))
    assert run.returncode == 0, run.stderr
    assert run.stderr == '' and run.stdout == ''
    return str(out)


def load(path):
    # yourdfpy only parses here; mesh files are checked separately (the .dae
    # meshes would need pycollada).
    return yourdfpy.URDF.load(path, load_meshes=False, build_collision_scene_graph=False,
                              load_collision_meshes=False)


def mesh_uris(urdf):
    return [g.geometry.mesh.filename for link in urdf.robot.links
            for g in list(link.visuals) + list(link.collisions) if g.geometry.mesh is not None]


@pytest.mark.parametrize('absolute', [False, True], ids=['package-uris', 'absolute-paths'])
@pytest.mark.parametrize('case', sorted(CASES))
def test_every_mesh_of_the_export_resolves_to_a_file(tmp_path, case, absolute):
    urdf = load(exported(tmp_path, CASES[case], absolute))
    uris = mesh_uris(urdf)
    assert len(uris) >= 14  # the arm alone has 7 links with a visual and a collision mesh
    for uri in uris:
        assert uri.startswith('/' if absolute else 'package://'), uri
        assert os.path.isfile(export.resolve_uri(uri)), uri


@pytest.mark.parametrize('case', sorted(CASES))
def test_independent_library_sees_the_same_tree_and_kinematics(tmp_path, case):
    path = exported(tmp_path, CASES[case], absolute=True)
    with open(path) as f:
        ours = ExpandedModel(f.read())
    urdf = load(path)
    assert sorted(urdf.link_map) == sorted(ours.links)
    assert urdf.base_link == ours.root()
    rng = np.random.default_rng(4)
    cfg = {}
    for name in urdf.actuated_joint_names:
        joint = urdf.joint_map[name]
        cfg[name] = rng.uniform(max(joint.limit.lower, -np.pi), min(joint.limit.upper, np.pi))
    urdf.update_cfg(cfg)
    for link in ours.links:
        np.testing.assert_allclose(urdf.get_transform(link, urdf.base_link), ours.to_root(link, cfg),
                                   atol=1e-9, err_msg=link)


def test_export_to_stdout_names_its_options():
    run = run_export('--ur-type', 'ur16e', '--no-gripper')
    assert run.returncode == 0, run.stderr
    assert 'ur_type=ur16e' in run.stdout and 'gripper=false' in run.stdout
    assert ExpandedModel(run.stdout).root() == 'base_link'


def test_help_documents_every_option():
    run = run_export('--help')
    assert run.returncode == 0
    for option in ('--ur-type', '--prefix', '--no-ft-sensor', '--no-gripper', '--world',
                   '--joint-limit-params', '--kinematics-params', '--physical-params',
                   '--visual-params', '--absolute-meshes', '--output'):
        assert option in run.stdout, option
    assert 'installed ur_description/config: ur3, ur3e, ur5, ur5e, ur10, ur10e, ur16e, ur20, ur30' in \
        ' '.join(run.stdout.split())


@pytest.mark.parametrize('options,words', [
    (['--ur-type', 'ur7'], ['config/ur7/joint_limits.yaml', 'ur3, ur3e, ur5, ur5e, ur10, ur10e, ur16e, ur20, ur30']),
    (['--kinematics-params', '/nonexistent/calibration.yaml'],
     ['No such file or directory', '/nonexistent/calibration.yaml']),
    (['--no-such-option'], ['unrecognized arguments: --no-such-option', '--help']),
    (['--ur-type'], ['--ur-type', 'expected one argument']),
    (['--prefix', 'arm-1_'], ["'arm-1_base_link'", 'TF frame name']),
])
def test_bad_options_are_one_line_and_write_nothing(tmp_path, options, words):
    out = tmp_path / 'model.urdf'
    run = run_export(*(options + ['-o', str(out)]))
    assert run.returncode == 1
    assert run.stdout == ''
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('export_urdf: error: '), run.stderr
    for word in words:
        assert word in lines[0], (word, lines[0])
    assert not out.exists()


def test_a_relative_parameter_file_is_taken_from_where_the_command_runs(tmp_path):
    # A calibration beside the user's shell, named as the shell names it: the shoulder height
    # it changes must show in the export (xacro alone would look for it beside the package's xacro).
    with open(os.path.join(UR_CONFIG_ROOT, 'ur3', 'default_kinematics.yaml')) as f:
        calibration = yaml.safe_load(f)
    calibration['kinematics']['shoulder']['z'] = 0.1525
    with open(str(tmp_path / 'my_robot_calibration.yaml'), 'w') as f:
        yaml.safe_dump(calibration, f)
    run = run_export('--no-gripper', '--kinematics-params', 'my_robot_calibration.yaml', cwd=str(tmp_path))
    assert run.returncode == 0, run.stderr
    assert ExpandedModel(run.stdout).origin_xyz('shoulder_pan_joint')[2] == pytest.approx(0.1525)
