"""The robot's own wrench at its TCP, from what the tool exerts on the flange: no ROS.

A UR reports one wrench of its own: `get_tcp_force()` in URScript (base
axes) and the driver's `wrench` topic (the TCP's axes, frame
`tool0_controller`). It is the external wrench acting on the tool at the
TCP, that is what the world exerts on the tool beyond the weight of the
configured payload (`set_payload`), less the offset `zero_ftsensor` took.

- An e-Series measures it with the sensor in its flange; the simulation reads
  MuJoCo's force and torque at the flange (``Cell.flange_wrench``).
- A CB3 has no sensor there: it estimates the wrench from the joints' motor
  currents, a reading that is off by several newtons, more while the arm
  moves. The simulation reports the flange's reading for a CB3 too, i.e. what a
  perfect estimate would give; the doc says so.
- Without physics nothing touches the tool: the wrench reads zero.

The payload's weight is compensated with the mass and centre of gravity the
robot was given (the installation's, then `set_payload`), so a wrong payload
shows as a force, as on the robot. Inertial forces of a moving tool are not
compensated (the robot's estimate does compensate them; the error here is
the tool's mass times its acceleration, well under a newton in the moves of
force-mode programs).
"""

import numpy as np

from ...kinematics import Model
from ..wrench_model import gravity_wrench


def mounted_payload(urdf_text, flange):
    """(mass kg, centre of gravity m in the flange's axes) of every link below `flange` in the model.

    What a user enters as the payload of an installation with this tool.
    """
    model = Model(urdf_text)
    below = [link for link in model.links if link != flange and _below(model, flange, link)]
    mass, moment = 0.0, np.zeros(3)
    for name in below:
        inertial = model.robot.link_map[name].inertial
        if inertial is None or not inertial.mass:
            continue
        origin = model.transform(flange, name)
        centre = origin[:3, :3].dot(inertial.origin.xyz if inertial.origin is not None else np.zeros(3))
        mass += inertial.mass
        moment += inertial.mass * (origin[:3, 3] + centre)
    return mass, tuple(moment / mass) if mass > 0 else (0.0, 0.0, 0.0)


def _below(model, ancestor, link):
    try:
        model.chain(ancestor, link)
    except ValueError:  # not a descendant
        return False
    return True


class TcpWrench(object):
    """The robot's wrench from the flange's. `payload` (mass, cog) is the robot's, as set_payload set it,
    passed on each call: the robot state is its one home."""

    def __init__(self):
        self.offset = np.zeros(6)   # zero_ftsensor's, in the flange's axes at the flange

    def _external_at_flange(self, flange_wrench, flange_rotation, payload):
        """The external wrench on the tool at the flange, in the flange's axes, payload and offset removed."""
        mass, cog = payload
        down = flange_rotation.T.dot((0.0, 0.0, -1.0))  # gravity's direction in the flange's axes
        weight = gravity_wrench(down[0], down[1], down[2], mass, cog)
        return np.asarray(flange_wrench, dtype=float) - np.asarray(weight) - self.offset

    def zero(self, flange_wrench, flange_rotation, payload):
        """zero_ftsensor: from now on, the present reading is zero (nothing to zero where nothing is measured)."""
        self.offset = np.zeros(6)
        if flange_wrench is None:
            return
        self.offset = self._external_at_flange(flange_wrench, flange_rotation, payload)

    def at_tcp(self, flange_wrench, flange_rotation, tcp, payload):
        """(base axes, tcp axes): the external wrench at the TCP (`tcp`: its 4x4 pose in the flange's frame).

        `flange_wrench`: what the tool exerts on the flange (N, N m; flange axes, about its origin), or
        None where nothing is measured (the kinematic simulation): zero.
        """
        if flange_wrench is None:
            return np.zeros(6), np.zeros(6)
        external = self._external_at_flange(flange_wrench, flange_rotation, payload)
        force, torque = external[:3], external[3:]
        # The same force about the TCP: the moment arm runs from the TCP to the flange's origin.
        # (np.cross written out: on 3-vectors it costs ten times this, and this runs every control period)
        x, y, z = tcp[:3, 3]
        torque = torque - np.array((y * force[2] - z * force[1], z * force[0] - x * force[2],
                                    x * force[1] - y * force[0]))
        tcp_axes = np.concatenate((tcp[:3, :3].T.dot(force), tcp[:3, :3].T.dot(torque)))
        base_axes = np.concatenate((flange_rotation.dot(force), flange_rotation.dot(torque)))
        return base_axes, tcp_axes
