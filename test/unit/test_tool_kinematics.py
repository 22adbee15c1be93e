"""ToolKinematics plans gripper_tcp to any pose in the arm's reach, from any start within the joint limits.

The targets are reachable by construction: each is the forward kinematics of joints within the limits
(its witness), tool-down over the table area the examples use and general poses. The starts are a grid
over the joint limits. The forward kinematics checked against is the expanded model's own.
"""
import itertools
import math
import os
import types

import numpy as np
import pytest
import rospkg
import yaml
from transforms3d.quaternions import mat2quat

from ur3_ft_gripper_description import clients, kinematics
from ur3_ft_gripper_description.model import description

JOINTS = list(clients.ARM_JOINTS)
# How close the planned tool comes to the target (m, rad).
POSE_TOLERANCE = 1e-6
# How close (rad, each joint) the planned joints are to the solution they should be.
JOINT_TOLERANCE = 1e-5
# The table area of the examples: gripper_tcp this far (m) from the base's axis, in front of the arm
# (x >= 0), this high over the table (m); the default world's objects stand in it.
TABLE_RADIUS = (0.15, 0.45)
TABLE_HEIGHT = (0.02, 0.30)
# Tool-down targets: one per cube of this side (m) of the table area.
CELL = 0.15
# A seed's branch is told apart only this far from where two branches meet: the wrist centre's distance
# (m) ahead of or behind the shoulder, and the sines of wrist_2 and the elbow. On a calibrated arm they
# meet a few millimetres from where they meet on the nominal one: a seed that close is in either.
BRANCH_MARGIN = (1e-6, 1e-6)
CALIBRATED_BRANCH_MARGIN = (0.01, 0.01)
# Witnesses stay further from where branches meet than the neighbours' offsets take them, and this far
# from the limits (rad).
WITNESS_MARGIN = (0.08, 0.25)
WITNESS_LIMIT_MARGIN = 0.2
BRANCHES = list(itertools.product((1, -1), repeat=3))


def calibrated_ur3(directory):
    """The UR3 with ur_description's default kinematics, every figure moved by its own amount: 0.1 to
    3.6 mm or mrad, a calibration's order (the tool moves by centimetres)."""
    default = os.path.join(rospkg.RosPack().get_path('ur_description'), 'config', 'ur3', 'default_kinematics.yaml')
    with open(default) as f:
        data = yaml.safe_load(f)
    sections = ('shoulder', 'upper_arm', 'forearm', 'wrist_1', 'wrist_2', 'wrist_3')
    keys = ('x', 'y', 'z', 'roll', 'pitch', 'yaw')
    for step, (section, key) in enumerate(itertools.product(sections, keys), 1):
        data['kinematics'][section][key] += 0.0001 * step
    path = os.path.join(str(directory), 'ur3_calibration.yaml')
    with open(path, 'w') as f:
        yaml.safe_dump(data, f)
    return description.to_xml(description.expand_model(dict(ur_type='ur3', kinematics_params=path)))


class Arm(object):
    """The expanded model, ToolKinematics on it as a script would build it, and checks in the model's terms."""

    def __init__(self, text):
        self.model = kinematics.Model(text)
        self.tool = clients.ToolKinematics(types.SimpleNamespace(get_param=lambda name: text))
        self.branch_margin = BRANCH_MARGIN
        self.lower = np.array([self.model.joints[j].limit.lower for j in JOINTS])
        self.upper = np.array([self.model.joints[j].limit.upper for j in JOINTS])

    def tcp(self, positions):
        return self.model.transform('base_link', 'gripper_tcp', dict(zip(JOINTS, positions)))

    def branch(self, positions, margin=None):
        """(shoulder, wrist, elbow), each +1 or -1, or None within `margin` of where two branches meet:
        the wrist centre (wrist_2_link) ahead of or behind the shoulder, the signs of wrist_2's and the
        elbow's sines."""
        q = dict(zip(JOINTS, positions))
        shoulder = self.model.transform('base_link', 'shoulder_link', q)
        centre = self.model.transform('base_link', 'wrist_2_link', q)[:2, 3] - shoulder[:2, 3]
        ahead, wrist, elbow = shoulder[:2, 0].dot(centre), math.sin(positions[4]), math.sin(positions[2])
        margin = margin or self.branch_margin
        if abs(ahead) < margin[0] or min(abs(wrist), abs(elbow)) < margin[1]:
            return None
        return tuple(int(np.sign(s)) for s in (ahead, wrist, elbow))

    def is_nearest_turn(self, joints, solution, seed):
        """Whether `joints` is `solution` with each joint turned by whole turns to lie nearest `seed`
        within the limits (either of two turns as near)."""
        for value, at, start, low, high in zip(solution, joints, seed, self.lower, self.upper):
            options = [value + turn * 2.0 * math.pi for turn in range(-2, 3)]
            options = [option for option in options if low - 1e-9 <= option <= high + 1e-9]
            nearest = min(abs(option - start) for option in options)
            if not any(abs(option - start) < nearest + 1e-9 and abs(option - at) <= JOINT_TOLERANCE
                       for option in options):
                return False
        return True

    def within(self, positions, margin=0.0):
        return bool(np.all(positions >= self.lower + margin) and np.all(positions <= self.upper - margin))

    def witness_branch(self, positions):
        """The branch of joints fit to be a witness, or None."""
        return self.branch(positions, WITNESS_MARGIN) if self.within(positions, WITNESS_LIMIT_MARGIN) else None


def pose_miss(target, pose):
    """(m, rad) from `pose` to `target`."""
    w, x, y, z = mat2quat(target[:3, :3].T.dot(pose[:3, :3]))
    angle = 2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), abs(w))
    return float(np.linalg.norm(target[:3, 3] - pose[:3, 3])), angle


def tool_down_witnesses(arm):
    """Joints holding the tool straight down, one per cube of the table area, the branches in turn.

    With wrist_2 at -pi/2 (+pi/2) and wrist_1 at -pi/2 (+pi/2) minus shoulder_lift and elbow, the
    wrist hangs vertical whatever the other joints do (a calibration tilts it by milliradians: the
    targets are still the model's forward kinematics).
    """
    cells = {}
    for pan, lift, elbow, hang, yaw in itertools.product(
            np.linspace(-math.pi, math.pi, 16, endpoint=False), np.linspace(-math.pi, math.pi, 24, endpoint=False),
            np.concatenate([np.linspace(-2.8, -0.4, 6), np.linspace(0.4, 2.8, 6)]), (-1.0, 1.0), (0.0, 0.9)):
        q = np.array([pan, lift, elbow, hang * math.pi / 2.0 - lift - elbow, hang * math.pi / 2.0, pan + yaw])
        x, y, z = arm.tool.tool_pose(q)[:3, 3]  # only to sort the samples: the target is the model's own
        if (TABLE_RADIUS[0] <= math.hypot(x, y) <= TABLE_RADIUS[1] and x >= 0.0
                and TABLE_HEIGHT[0] <= z <= TABLE_HEIGHT[1]):
            branch = arm.witness_branch(q)
            if branch is not None:
                cells.setdefault((int(x // CELL), int(y // CELL), int(z // CELL)), {}).setdefault(branch, q)
    witnesses, uses = [], dict.fromkeys(BRANCHES, 0)
    for _, options in sorted(cells.items()):
        branch = min(options, key=lambda b: (uses[b], BRANCHES.index(b)))  # the least used so far
        uses[branch] += 1
        witnesses.append(options[branch])
    for q in witnesses:
        assert arm.tcp(q)[2, 2] < math.cos(math.pi - 0.1), 'the tool does not point down at %s' % q
    return witnesses


def general_witnesses(arm, count=10):
    """Joints anywhere within the limits, away from where branches meet."""
    rng = np.random.RandomState(7)
    found = []
    while len(found) < count:
        q = rng.uniform(arm.lower, arm.upper)
        if arm.witness_branch(q) is not None:
            found.append(q)
    return found


def seed_grid(arm, levels):
    """Seeds spread over the joint limits: each joint at the fractions `levels[j]` of its range, all
    combinations, and the two corners of the limits."""
    per_joint = [low + np.array(fractions) * (high - low)
                 for low, high, fractions in zip(arm.lower, arm.upper, levels)]
    return [np.array(q) for q in itertools.product(*per_joint)] + [arm.lower.copy(), arm.upper.copy()]


# The arm's own joints (shoulder_pan, shoulder_lift, elbow) at three points of their range, the wrists at
# two where they are not straight: 216 seeds, and the corners. The other models take two points
# everywhere: 64, and the corners.
FINE = [(1 / 6.0, 1 / 2.0, 5 / 6.0)] * 3 + [(1 / 3.0, 2 / 3.0)] * 3
COARSE = [(1 / 3.0, 2 / 3.0)] * 6


@pytest.fixture(scope='module', params=['ur3', 'ur5e', 'ur3-calibrated'])
def arm(request, configured_model, tmp_path_factory):
    if request.param == 'ur3-calibrated':
        arm = Arm(calibrated_ur3(tmp_path_factory.mktemp('calibration')))
        arm.branch_margin = CALIBRATED_BRANCH_MARGIN
    else:
        arm = Arm(configured_model(request.param, True, True).text)
    arm.levels = FINE if request.param == 'ur3' else COARSE
    arm.tool_down, arm.general = tool_down_witnesses(arm), general_witnesses(arm)
    return arm


def test_every_target_is_reached_from_every_seed_nearest_in_the_seeds_branch(arm):
    cells = {tuple(int(v // CELL) for v in arm.tcp(q)[:3, 3]) for q in arm.tool_down}
    assert len(cells) == len(arm.tool_down) >= 20 and len({cell[2] for cell in cells}) >= 2, sorted(cells)
    # Both shoulders, both wrists, both elbows: every branch of the arm holds some target.
    assert {arm.branch(q) for q in arm.tool_down} == set(BRANCHES)
    witnesses = arm.tool_down + arm.general
    seeds = seed_grid(arm, arm.levels)
    seed_branches = [arm.branch(seed) for seed in seeds]
    failures, same_branch = [], 0
    for witness in witnesses:
        target, branch = arm.tcp(witness), arm.branch(witness)
        for seed, seed_branch in zip(seeds, seed_branches):
            where = 'target %s (witness %s) from seed %s' % (np.round(target[:3, 3], 3).tolist(),
                                                             np.round(witness, 3).tolist(), np.round(seed, 3).tolist())
            try:
                joints = np.array(arm.tool.joints_for(target, seed))
            except clients.CellError as error:
                failures.append('%s: %s' % (where, error))
                continue
            miss = pose_miss(target, arm.tcp(joints))
            if not arm.within(joints):
                failures.append('%s: joints %s beyond the limits' % (where, np.round(joints, 3).tolist()))
            elif miss[0] > POSE_TOLERANCE or miss[1] > POSE_TOLERANCE:
                failures.append('%s: missed by %.2g m, %.2g rad' % (where, miss[0], miss[1]))
            elif seed_branch == branch:
                # The seed's branch reaches the target at the witness: the plan is the witness, turned the
                # short way from the seed, not another branch's solution nor a turn further.
                same_branch += 1
                if not arm.is_nearest_turn(joints, witness, seed):
                    failures.append('%s: %s, not the witness turned nearest the seed' % (
                        where, np.round(joints, 3).tolist()))
    pairs = len(witnesses) * len(seeds)
    assert not failures, '%d of %d (target, seed) pairs failed, e.g.\n%s' % (
        len(failures), pairs, '\n'.join(failures[:10]))
    assert same_branch >= len(witnesses), 'too few seeds share a target\'s branch to check the choice'


def test_from_a_neighbour_of_a_solution_the_plan_is_that_solution(arm):
    """A step along a path: no swing through a far configuration when the near one is there."""
    offsets = [0.1 * np.array(signs) for signs in ((1, 1, 1, 1, 1, 1), (-1, -1, -1, -1, -1, -1),
                                                   (1, -1, 1, -1, 1, -1), (-1, 1, 1, -1, -1, 1))]
    failures = []
    witnesses = arm.tool_down + arm.general
    for witness in witnesses:
        for offset in offsets:
            where = 'from %s' % np.round(witness + offset, 3).tolist()
            try:
                joints = np.array(arm.tool.joints_for(arm.tcp(witness), witness + offset))
            except clients.CellError as error:
                failures.append('%s: %s' % (where, error))
                continue
            if np.max(np.abs(joints - witness)) > JOINT_TOLERANCE:
                failures.append('%s: %s, not %s' % (where, np.round(joints, 3).tolist(),
                                                    np.round(witness, 3).tolist()))
    assert not failures, '%d of %d failed, e.g.\n%s' % (
        len(failures), len(witnesses) * len(offsets), '\n'.join(failures[:10]))


def test_the_examples_paths_go_from_the_start_pose_to_each_object_without_swinging(arm):
    start = np.array([0.0, -math.pi / 2.0, math.pi / 2.0, -math.pi / 2.0, -math.pi / 2.0, 0.0])
    # The default world's objects, and the pose the pick of the plate planned for (x, y, z, yaw).
    for x, y, z, yaw in ((0.30, -0.15, 0.11, 0.0), (0.20, -0.25, 0.105, 0.0), (0.38, -0.02, 0.16, 0.0),
                         (0.38, -0.02, 0.045, 0.0), (0.2986, 0.1123, 0.08, 0.0), (0.30, -0.15, 0.11, 1.2)):
        path = [np.array(joints) for joints in arm.tool.path_to(start, x, y, z, clear_height=0.16, yaw=yaw)]
        pose = arm.tcp(path[-1])
        assert max(pose_miss(arm.tool.tool_down(x, y, z, yaw), pose)) <= POSE_TOLERANCE, (x, y, z, yaw)
        # Up, over, down: the wrist stays the same way up and no joint turns further than the move needs.
        for before, after in zip([start] + path, path):
            assert arm.branch(after) == arm.branch(start), (x, y, z, yaw, np.round(after, 3).tolist())
            assert np.max(np.abs(after - before)) < math.pi, (x, y, z, yaw, np.round(after, 3).tolist())


def test_a_pose_beyond_the_arms_radius_is_out_of_reach_in_one_line(arm):
    # Further from base_link than every link of the chain laid end to end.
    chain = arm.model.chain('base_link', 'gripper_tcp')
    radius = sum(np.linalg.norm(joint.origin.xyz) for joint in chain if joint.origin is not None)
    far = arm.tool.tool_down(radius + 0.1, 0.0, 0.2)
    with pytest.raises(clients.CellError) as raised:
        arm.tool.joints_for(far, np.zeros(6))
    message = str(raised.value)
    assert len(message.splitlines()) == 1 and 'out of the arm\'s reach' in message, message
