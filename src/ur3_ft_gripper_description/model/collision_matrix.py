"""Which link pairs a planner need not check, found the way MoveIt's setup assistant finds them.

For one exported URDF (absolute mesh paths) this module loads the collision
geometry with pinocchio and coal (FCL's successor, as MoveIt uses FCL), then
sorts every pair of links with collision geometry, in the setup assistant's
order (moveit_setup_assistant's compute_default_collisions):

* ``Adjacent``: a link and its nearest ancestor with geometry (frames without
  geometry between them, such as ``flange`` and ``tool0``, do not separate them);
* ``Default``: in collision at the default state (every joint 0);
* ``Always``: in collision in at least 95 of 100 random states, repeated
  until a round finds no new pair;
* ``Never``: in collision in none of ``samples`` random states.

Random states draw every actuated joint uniformly within its limits; mimic
joints follow their leader's law, as on the real mechanism. Every other pair
is left for the planner to check. ``tools/generate_collision_matrix.py``
writes the result for every model configuration into
``config/collision_matrix.yaml``, which ``config/ur3_ft_gripper.srdf.xacro``
reads. Needs pinocchio (PyPI ``pin``) and numpy; imported by that tool and
the consumer tests only.
"""

import xml.etree.ElementTree as ElementTree

import numpy as np

ALWAYS_FRACTION = 0.95
ALWAYS_ROUND = 100
REASONS = ('Adjacent', 'Default', 'Always', 'Never')


class CollisionModel(object):
    """A URDF's collision geometry in pinocchio + coal, with its mimic joints followed."""

    def __init__(self, urdf_path):
        import pinocchio
        self.pin = pinocchio
        self.model = pinocchio.buildModelFromUrdf(urdf_path)
        self.geometry = pinocchio.buildGeomFromUrdf(self.model, urdf_path, pinocchio.GeometryType.COLLISION)
        root = ElementTree.parse(urdf_path).getroot()
        self.parent = {j.find('child').get('link'): j.find('parent').get('link')
                       for j in root.findall('joint')}
        self.mimic = {}
        for joint in root.findall('joint'):
            mimic = joint.find('mimic')
            if mimic is not None:
                self.mimic[joint.get('name')] = (mimic.get('joint'), float(mimic.get('multiplier', 1.0)),
                                                 float(mimic.get('offset', 0.0)))
        self.link_of = [self.model.frames[g.parentFrame].name for g in self.geometry.geometryObjects]
        self.links = sorted(set(self.link_of))
        self.geometry.addAllCollisionPairs()
        self.data = self.model.createData()
        self.geometry_data = pinocchio.GeometryData(self.geometry)
        self.pair_links = []
        for pair in self.geometry.collisionPairs:
            a, b = self.link_of[pair.first], self.link_of[pair.second]
            self.pair_links.append(tuple(sorted((a, b))) if a != b else None)
        self.actuated = [name for name in self.model.names[1:] if name not in self.mimic]
        self.check_only(None)

    def joint_index(self, name):
        return self.model.joints[self.model.getJointId(name)].idx_q

    def configuration(self, positions=None):
        """q with `positions` ({actuated joint: value}, others 0) and every mimic joint on its law."""
        q = np.zeros(self.model.nq)
        for name, value in (positions or {}).items():
            q[self.joint_index(name)] = value
        for name, (leader, multiplier, offset) in self.mimic.items():
            q[self.joint_index(name)] = q[self.joint_index(leader)] * multiplier + offset
        return q

    def random_configuration(self, rng):
        positions = {}
        for name in self.actuated:
            i = self.joint_index(name)
            positions[name] = rng.uniform(self.model.lowerPositionLimit[i], self.model.upperPositionLimit[i])
        return self.configuration(positions)

    def check_only(self, pairs):
        """Compute collisions of these link pairs only (None: all pairs of different links)."""
        self.active = []
        for k, links in enumerate(self.pair_links):
            on = links is not None and (pairs is None or links in pairs)
            if on:
                self.geometry_data.activateCollisionPair(k)
                self.active.append(k)
            else:
                self.geometry_data.deactivateCollisionPair(k)

    def colliding_pairs(self, q, ignore=()):
        """Sorted (link, link) pairs in contact at q among the active ones, leaving out `ignore`."""
        self.pin.computeCollisions(self.model, self.data, self.geometry, self.geometry_data, q, False)
        return {self.pair_links[k] for k in self.active if self.pair_links[k] not in ignore and
                self.geometry_data.collisionResults[k].isCollision()}

    def adjacent_pairs(self):
        """Each link with geometry and its nearest ancestor with geometry."""
        pairs = set()
        for link in self.links:
            ancestor = self.parent.get(link)
            while ancestor is not None and ancestor not in self.links:
                ancestor = self.parent.get(ancestor)
            if ancestor is not None:
                pairs.add(tuple(sorted((link, ancestor))))
        return pairs


def compute(model, samples, seed=0):
    """{(link, link): reason} of the pairs a planner need not check, and how many were sampled."""
    rng = np.random.default_rng(seed)
    reasons = {pair: 'Adjacent' for pair in model.adjacent_pairs()}
    for pair in model.colliding_pairs(model.configuration(), ignore=reasons):
        reasons[pair] = 'Default'
    while True:
        counts = {}
        for _ in range(ALWAYS_ROUND):
            for pair in model.colliding_pairs(model.random_configuration(rng), ignore=reasons):
                counts[pair] = counts.get(pair, 0) + 1
        always = [pair for pair, n in counts.items() if n >= ALWAYS_FRACTION * ALWAYS_ROUND]
        if not always:
            break
        reasons.update({pair: 'Always' for pair in always})
    # A pair seen in contact once is settled: only the others are checked on.
    all_pairs = {tuple(sorted((a, b))) for i, a in enumerate(model.links) for b in model.links[i + 1:]}
    open_pairs = all_pairs - set(reasons)
    model.check_only(open_pairs)
    for _ in range(samples):
        seen = model.colliding_pairs(model.random_configuration(rng))
        if seen:
            open_pairs -= seen
            model.check_only(open_pairs)
    model.check_only(None)
    reasons.update({pair: 'Never' for pair in open_pairs})
    return reasons


def largest_free_value(model, joint, disabled, positions=None, tolerance=1e-4):
    """The largest value of `joint` (0 .. its upper limit) free of collisions but the `disabled` pairs.

    Bisection between 0, which must be free, and the upper limit; returned
    rounded down to 1e-3 rad.
    """
    positions = dict(positions or {})
    i = model.joint_index(joint)
    low, high = 0.0, float(model.model.upperPositionLimit[i])

    def free(value):
        positions[joint] = value
        return not model.colliding_pairs(model.configuration(positions), ignore=disabled)

    if not free(low):
        raise ValueError('%s = 0 is already in collision' % joint)
    if free(high):
        return high
    while high - low > tolerance:
        middle = (low + high) / 2.0
        low, high = (middle, high) if free(middle) else (low, middle)
    return float(np.floor(low * 1000.0) / 1000.0)
