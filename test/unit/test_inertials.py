"""Mass properties: valid everywhere, the manufacturer's figures for the Robotiq parts, one home for each."""
import os
import xml.etree.ElementTree as ElementTree

import pytest
import yaml

from ur3_ft_gripper_description.model import export, inertials, inertials_from_meshes
from ur3_ft_gripper_testing.model import PACKAGE_DIR, TOGGLES, robotiq_variant

FIGURES = os.path.join(PACKAGE_DIR, 'config', 'robotiq_mass.yaml')
TABLE = os.path.join(PACKAGE_DIR, 'config', 'link_inertials.yaml')
FT300_LINKS = list(inertials.PARTS['ft300'])
GRIPPER_LINKS = list(inertials.PARTS['gripper_2f_140'])


def figures():
    with open(FIGURES) as f:
        return yaml.safe_load(f)


def has_geometry(model, link):
    lk = model.robot.link_map[link]
    return bool(lk.visuals or lk.collisions)


@pytest.mark.parametrize('toggles', TOGGLES, ids=lambda t: '-'.join(k for k, v in t.items() if v) or 'arm')
def test_every_link_with_geometry_has_a_physical_inertial(configured_model, toggles):
    model = configured_model('ur3', **toggles)
    for link in model.links:
        if has_geometry(model, link):
            model.assert_physical_inertial(link)


@pytest.mark.parametrize('toggles', TOGGLES, ids=lambda t: '-'.join(k for k, v in t.items() if v) or 'arm')
def test_no_link_but_the_root_is_left_without_an_inertial(configured_model, toggles):
    model = configured_model('ur3', **toggles)
    bare = [link for link in model.links if model.robot.link_map[link].inertial is None]
    assert bare == [model.root()]
    for link in model.links:
        if not has_geometry(model, link) and link != model.root():
            # More than libsdformat's zero (1e-6 kg), far less than anything real.
            assert model.mass(link) == inertials.FRAME['mass'], link
            model.assert_physical_inertial(link)


def test_root_gets_a_frames_mass_below_a_world_link(expand_model):
    model = expand_model(world='true')
    assert model.mass('base_link') == inertials.FRAME['mass']
    assert model.robot.link_map['world'].inertial is None


def test_ft300_has_the_manuals_mass_and_centre_of_mass(default_model):
    mass, com = default_model.com_in('tool0', FT300_LINKS)
    assert mass == pytest.approx(figures()['ft300']['mass'], abs=1e-6)
    assert com[2] == pytest.approx(figures()['ft300']['com_z_from_tool0'], abs=1e-5)
    assert abs(com[0]) < 1e-3 and abs(com[1]) < 1e-3


def test_ft300_with_open_gripper_has_the_manuals_mass_and_centre_of_mass(default_model):
    mass, com = default_model.com_in('tool0', FT300_LINKS + GRIPPER_LINKS)
    both = figures()['ft300_with_2f140']
    assert mass == pytest.approx(both['mass'], abs=1e-6)
    assert com[2] == pytest.approx(both['com_z_from_tool0'], abs=1e-5)
    assert abs(com[0]) < 1e-3 and abs(com[1]) < 1e-3


def test_each_centre_of_mass_lies_within_its_links_collision_mesh_bounds(default_model):
    for link in FT300_LINKS + GRIPPER_LINKS:
        lk = default_model.robot.link_map[link]
        mesh = inertials_from_meshes._collision_mesh(lk.collisions[0], export.resolve_uri)
        com = lk.inertial.origin.xyz
        low, high = mesh.bounds
        assert all(lo - 1e-9 <= c <= hi + 1e-9 for c, lo, hi in zip(com, low, high)), (link, com, mesh.bounds)


def test_stored_table_is_what_the_meshes_and_the_manual_give():
    links, densities = inertials_from_meshes.compute_table(figures())
    with open(TABLE) as f:
        stored = yaml.safe_load(f)['links']
    assert sorted(stored) == sorted(links)
    # The two robotiq layouts put finger_joint 1 micrometre apart, which moves
    # the split between palm and fingers by a few parts per million.
    for name, entry in links.items():
        assert stored[name]['mass'] == pytest.approx(entry['mass'], rel=1e-4), (name, robotiq_variant())
        assert stored[name]['com'] == pytest.approx(entry['com'], abs=1e-6), name
        for key, value in entry['inertia'].items():
            assert stored[name]['inertia'][key] == pytest.approx(value, rel=1e-4, abs=1e-10), (name, key)
    # Densities of real materials: the FT 300's aluminium coupling plate comes out as aluminium.
    assert densities['ft300_mounting_plate'] == pytest.approx(2700, rel=0.02)
    assert all(500 < d < 8000 for d in densities.values()), densities


def test_prefixed_robots_get_the_inertials_too(configured_model):
    model = configured_model('ur3', True, True, prefix='left_')
    for link in FT300_LINKS + GRIPPER_LINKS:
        model.assert_physical_inertial('left_' + link)
    assert model.com_in('left_tool0', ['left_' + n for n in FT300_LINKS])[0] == pytest.approx(0.3)


def test_transmission_interfaces_are_ros_control_names(default_model):
    interfaces = [t.text for t in ElementTree.fromstring(default_model.text).iter('hardwareInterface')]
    assert interfaces, 'no transmissions'
    for name in interfaces:
        assert name.startswith('hardware_interface/') and name.count('/') == 1, name
