"""force_mode's law (devices/ur_arm/force_mode.py) pressing the tool on the physics cell's table.

The robot's side is driven as the arm's core drives it: every control cycle
its own TCP wrench (tcp_wrench.TcpWrench over the cell's flange reading) goes
into ForceMode, whose displacement moves the TCP target, which the joints
follow through the model's inverse kinematics. The truths: the contact force
the table puts on the robot (MuJoCo's), and the FT 300 (zeroed before) reading
the commanded force, at the control periods of a CB3 (8 ms) and an e-Series
(2 ms).
"""
import numpy as np
import pytest

from ur3_ft_gripper_description.devices.ur_arm import force_mode as fm
from ur3_ft_gripper_description.devices.ur_arm import tcp_wrench as tw
from ur3_ft_gripper_description.devices.ur_arm.joints import JointCommand
from ur3_ft_gripper_testing.physics import STANDARD_GRAVITY, Arm

PRESS_LIMITS = [0.1, 0.1, 0.05, 0.17, 0.17, 0.17]  # m/s, rad/s: 5 cm/s towards the table


class Pressing(object):
    """The cell's arm under one force_mode, with the robot's wrench as the arm's core computes it."""

    def __init__(self, cell, period):
        self.cell, self.period = cell, period
        self.arm = Arm(cell)
        self.arm.hold(0.5)
        self.robot_wrench = tw.TcpWrench()
        self.payload = tw.mounted_payload(cell.urdf_text, 'tool0')
        self.q = self.arm.motion.reference.copy()
        self.target = self.arm.kinematics.forward(self.q)
        self.ft_zero = np.array(cell.wrench())

    def tcp_wrench(self):
        """(base axes, tcp axes): the robot's own wrench now (the TCP at the flange)."""
        now = self.arm.kinematics.forward(self.cell.arm_position)
        return self.robot_wrench.at_tcp(self.cell.flange_wrench(), now[:3, :3], np.eye(4), self.payload)

    def run(self, mode, seconds):
        """Step `mode` for `seconds`; [(robot wrench in tcp axes, zeroed FT 300, tool0 position)] per cycle."""
        log = []
        for _ in range(int(round(seconds / self.period))):
            base, tcp = self.tcp_wrench()
            linear, angular = mode.step(self.period, self.target[:3, 3], base)
            self.target = fm.displaced(self.target, linear, angular)
            self.q = self.arm.kinematics.inverse(self.target, self.q, tolerance=1e-10)
            self.arm.motion.step(JointCommand('MOVE', self.q), self.period)
            assert self.arm.motion.protective_stop is None, self.arm.motion.protective_stop
            log.append((tcp, np.array(self.cell.wrench()) - self.ft_zero,
                        self.arm.kinematics.forward(self.cell.arm_position)[:3, 3]))
        return log


def mean(rows):
    return np.mean(np.array(rows), axis=0)


def test_at_rest_the_robots_wrench_with_the_mounted_payload_reads_zero(make_cell):
    pressing = Pressing(make_cell(), 0.008)
    mass, cog = pressing.payload
    assert mass == pytest.approx(1.275, abs=0.01)  # FT 300 (0.300) + 2F-140 with coupling, the model's
    assert np.allclose(pressing.tcp_wrench()[0], 0.0, atol=0.02)
    # Without the payload the robot reads the tool's weight, downwards in the base frame.
    pressing.payload = (0.0, (0.0, 0.0, 0.0))
    assert pressing.tcp_wrench()[0][2] == pytest.approx(-mass * STANDARD_GRAVITY, rel=0.01)


@pytest.mark.parametrize('period', [0.008, 0.002], ids=['CB3', 'e-Series'])
@pytest.mark.parametrize('force', [10.0, 20.0, 40.0])
def test_pressing_on_the_table_settles_at_the_commanded_force(make_cell, period, force):
    pressing = Pressing(make_cell(), period)
    mode = fm.ForceMode(pressing.target, [0, 0, 1, 0, 0, 0], [0, 0, force, 0, 0, 0], 2, PRESS_LIMITS)
    pressing.run(mode, 3.0)
    began, impulse = pressing.cell.time, pressing.cell.contact_impulse()
    steady = pressing.run(mode, 1.0)
    robot_fz, ft300_fz = mean([r[0] for r in steady])[2], mean([r[1] for r in steady])[2]
    # Over the same second: a contact's force changes from one timestep to the next.
    contact = (pressing.cell.contact_impulse() - impulse) / (pressing.cell.time - began)
    # The table pushes the tool up with the force the robot applies down (tool z points down).
    assert contact[2] == pytest.approx(force, rel=0.05, abs=0.5)
    assert -ft300_fz == pytest.approx(force, rel=0.05, abs=0.5)
    assert robot_fz == pytest.approx(ft300_fz, abs=1.0)


def test_compliant_along_x_and_y_with_no_force_there_the_tool_does_not_drift(make_cell):
    pressing = Pressing(make_cell(), 0.008)
    mode = fm.ForceMode(pressing.target, [1, 1, 1, 0, 0, 0], [0, 0, 20.0, 0, 0, 0], 2, PRESS_LIMITS)
    log = pressing.run(mode, 4.0)
    start, end = log[-int(round(1.0 / 0.008))][2], log[-1][2]
    assert np.linalg.norm((end - start)[:2]) < 0.001  # m in the last second: under 1 mm/s
    assert -mean([r[1] for r in log[-50:]])[2] == pytest.approx(20.0, rel=0.05, abs=0.5)


def test_in_free_air_the_compliant_axis_moves_at_its_speed_limit(make_cell):
    pressing = Pressing(make_cell(), 0.008)
    # Pulling up (-z of the tool), away from the table: nothing pushes back.
    mode = fm.ForceMode(pressing.target, [0, 0, 1, 0, 0, 0], [0, 0, -10.0, 0, 0, 0], 2, PRESS_LIMITS)
    log = pressing.run(mode, 1.0)
    rise = (log[-1][2] - log[-26][2])[2] / (25 * 0.008)
    assert rise == pytest.approx(0.05, rel=0.03)
