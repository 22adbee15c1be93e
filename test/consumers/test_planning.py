"""The SRDF as planners read it: pinocchio + coal (which read SRDF themselves) and python-fcl."""
import itertools
import os
import subprocess
import xml.etree.ElementTree as ElementTree

import fcl
import numpy as np
import pinocchio
import pytest
import trimesh
import yaml

from conftest import PACKAGE_DIR, exported_urdf, srdf, srdf_mappings
from ur3_ft_gripper_description.model import collision_matrix

ARM_STATES = ('home', 'up')
GRIPPER_STATES = ('open', 'closed')


class Planner(object):
    """The exported URDF in pinocchio (mimic joints on their law) with the SRDF applied."""

    def __init__(self, options, apply_srdf=True):
        self.urdf = exported_urdf(*options)
        self.srdf = srdf(*srdf_mappings(options))
        self.model = pinocchio.buildModelFromUrdf(self.urdf, mimic=True)
        self.geometry = pinocchio.buildGeomFromUrdf(self.model, self.urdf, pinocchio.GeometryType.COLLISION)
        self.geometry.addAllCollisionPairs()
        if apply_srdf:
            pinocchio.removeCollisionPairs(self.model, self.geometry, self.srdf)
        pinocchio.loadReferenceConfigurations(self.model, self.srdf)
        self.data = self.model.createData()
        self.geometry_data = pinocchio.GeometryData(self.geometry)
        self.semantic = ElementTree.parse(self.srdf).getroot()

    def state(self, *names):
        """q of the named states together (each sets its group's joints)."""
        q = pinocchio.neutral(self.model)
        for name in names:
            reference = self.model.referenceConfigurations[name]
            for element in self.semantic.findall("group_state[@name='%s']/joint" % name):
                i = self.model.joints[self.model.getJointId(element.get('name'))].idx_q
                q[i] = reference[i]
        return q

    def link_of(self, geometry_index):
        return self.model.frames[self.geometry.geometryObjects[geometry_index].parentFrame].name

    def coal_collisions(self, q):
        pinocchio.computeCollisions(self.model, self.data, self.geometry, self.geometry_data, q, False)
        return sorted((self.link_of(p.first), self.link_of(p.second))
                      for k, p in enumerate(self.geometry.collisionPairs)
                      if self.geometry_data.collisionResults[k].isCollision())

    def disabled(self):
        return {tuple(sorted((d.get('link1'), d.get('link2')))): d.get('reason')
                for d in self.semantic.findall('disable_collisions')}

    def fcl_collisions(self, q):
        """Pairs in contact at q by python-fcl on the meshes (pinocchio only for the poses)."""
        pinocchio.updateGeometryPlacements(self.model, self.data, self.geometry, self.geometry_data, q)
        objects = {}
        for k, geometry in enumerate(self.geometry.geometryObjects):
            if os.path.isfile(geometry.meshPath):
                mesh = trimesh.load(geometry.meshPath, force='mesh')
                mesh.apply_scale(geometry.meshScale)
                model = fcl.BVHModel()
                model.beginModel(len(mesh.vertices), len(mesh.faces))
                model.addSubModel(np.asarray(mesh.vertices), np.asarray(mesh.faces))
                model.endModel()
            else:  # the finger pads are URDF boxes
                model = fcl.Box(*(2 * np.asarray(geometry.geometry.halfSide)))
            placement = self.geometry_data.oMg[k]
            objects[k] = fcl.CollisionObject(model, fcl.Transform(placement.rotation, placement.translation))
        disabled = self.disabled()
        found = []
        for a, b in itertools.combinations(sorted(objects), 2):
            links = tuple(sorted((self.link_of(a), self.link_of(b))))
            if links[0] == links[1] or links in disabled:
                continue
            if fcl.collide(objects[a], objects[b], fcl.CollisionRequest(), fcl.CollisionResult()):
                found.append(links)
        return found


@pytest.fixture(scope='module')
def planner():
    return Planner([])


def test_srdf_has_upstreams_groups_and_the_gripper(planner):
    root = planner.semantic
    assert root.get('name') == ElementTree.parse(planner.urdf).getroot().get('name')
    chain = root.find("group[@name='manipulator']/chain")
    assert (chain.get('base_link'), chain.get('tip_link')) == ('base_link', 'tool0')
    assert root.find("group[@name='gripper']/link[@name='left_inner_finger_pad']") is not None
    effector = root.find('end_effector')
    assert (effector.get('parent_link'), effector.get('group'), effector.get('parent_group')) == (
        'tool0', 'gripper', 'manipulator')
    assert sorted(g.get('name') for g in root.findall('group_state')) == sorted(ARM_STATES + GRIPPER_STATES)
    closed = float(root.find("group_state[@name='closed']/joint[@name='finger_joint']").get('value'))
    assert 0.69 <= closed <= 0.7


def test_upstream_arm_states_are_kept(planner):
    # ur3_moveit_config lives in ur_description's repository (universal_robot).
    description = subprocess.run(['rospack', 'find', 'ur_description'], stdout=subprocess.PIPE,
                                 universal_newlines=True, check=True).stdout.strip()
    upstream = os.path.join(os.path.dirname(description), 'ur3_moveit_config', 'config', 'ur3.srdf')
    theirs = ElementTree.parse(upstream).getroot()
    for name in ARM_STATES:
        values = {j.get('name'): float(j.get('value'))
                  for j in theirs.findall("group_state[@name='%s']/joint" % name)}
        assert {j.get('name'): float(j.get('value'))
                for j in planner.semantic.findall("group_state[@name='%s']/joint" % name)} == values


@pytest.mark.parametrize('options',
                         [[], ['--no-ft-sensor'], ['--no-gripper'], ['--no-ft-sensor', '--no-gripper']],
                         ids=['ft_sensor-gripper', 'gripper', 'ft_sensor', 'arm'])
def test_every_named_state_is_free_of_collisions_under_coal_and_fcl(options):
    planner = Planner(options)
    gripper_states = GRIPPER_STATES if '--no-gripper' not in options else (None,)
    for arm, gripper in itertools.product(ARM_STATES, gripper_states):
        names = (arm, gripper) if gripper else (arm,)
        q = planner.state(*names)
        assert planner.coal_collisions(q) == [], names
        assert planner.fcl_collisions(q) == [], names


def test_without_the_srdf_the_linkage_collides_with_itself(planner):
    """The check above is not empty: the 2F-140's linkage pins are in contact at every opening."""
    bare = Planner([], apply_srdf=False)
    adjacent = {p for p, reason in planner.disabled().items() if reason == 'Adjacent'}
    found = {tuple(sorted(p)) for p in bare.coal_collisions(planner.state('home', 'open'))} - adjacent
    assert ('left_inner_finger', 'left_inner_knuckle') in found


def test_pads_closing_past_the_closed_state_touch(planner):
    q = planner.state('home', 'closed')
    q[planner.model.joints[planner.model.getJointId('finger_joint')].idx_q] = 0.7
    assert ('left_inner_finger_pad', 'right_inner_finger_pad') in planner.coal_collisions(q)


def test_pairs_never_in_collision_stay_apart_in_fresh_random_states(planner):
    never = {p for p, reason in planner.disabled().items() if reason == 'Never'}
    bare = pinocchio.buildGeomFromUrdf(planner.model, planner.urdf, pinocchio.GeometryType.COLLISION)
    bare.addAllCollisionPairs()
    bare_data = pinocchio.GeometryData(bare)
    rng = np.random.default_rng(12345)
    low, high = planner.model.lowerPositionLimit, planner.model.upperPositionLimit
    for _ in range(500):
        q = rng.uniform(low, high)
        pinocchio.computeCollisions(planner.model, planner.data, bare, bare_data, q, False)
        for k, pair in enumerate(bare.collisionPairs):
            if bare_data.collisionResults[k].isCollision():
                links = tuple(sorted(planner.model.frames[bare.geometryObjects[i].parentFrame].name
                                     for i in (pair.first, pair.second)))
                assert links not in never, (links, q)


def test_stored_matrix_is_what_the_tool_computes():
    with open(os.path.join(PACKAGE_DIR, 'config', 'collision_matrix.yaml')) as f:
        stored = yaml.safe_load(f)
    model = collision_matrix.CollisionModel(exported_urdf())
    reasons = collision_matrix.compute(model, stored['samples'])
    assert stored['samples'] >= 10000  # MoveIt setup assistant's default
    assert stored['disable_collisions']['ur3']['ft_sensor_gripper'] == [
        [a, b, reasons[(a, b)]] for a, b in sorted(reasons)]
    assert stored['gripper_closed'] == collision_matrix.largest_free_value(model, 'finger_joint', set(reasons))


def test_prefixed_srdf_names_the_prefixed_models_links():
    urdf = ElementTree.parse(exported_urdf('--prefix', 'left_')).getroot()
    links = {link.get('name') for link in urdf.findall('link')}
    joints = {joint.get('name') for joint in urdf.findall('joint')}
    semantic = ElementTree.parse(srdf('prefix:=left_')).getroot()
    named = ([d.get(k) for d in semantic.findall('disable_collisions') for k in ('link1', 'link2')]
             + [g.get('name') for g in semantic.iter('link')])
    assert named and set(named) <= links
    assert {j.get('name') for j in semantic.iter('joint')} <= joints
