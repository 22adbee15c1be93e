"""How the simulated joints follow their commands, without ROS.

ur_robot_driver streams the controllers' joint positions to the robot's
servoj, whose `lookahead_time` (ur_control.launch's servoj_lookahead_time,
0.03 s by default) "smoothens the trajectory with this lookahead time"
(URScript manual): the joints are taken to follow the command as a
first-order lag with that time constant, never faster than the model's
velocity limits and never beyond its position limits. So the arm ends a
motion a few hundredths of a second after its command, as the real one
does, and a trajectory asked to stop within a goal time shorter than that
fails its goal tolerance (ur_robot_driver's own integration test expects this).
"""

import numpy as np


def follow(position, command, dt, lag, velocity_limits, lower, upper):
    """(position, velocity) of the joints after dt seconds of following `command`."""
    position = np.asarray(position, dtype=float)
    if dt <= 0.0:
        return position.copy(), np.zeros_like(position)
    share = 1.0 if lag <= 0.0 else min(1.0, dt / lag)
    step = (np.asarray(command, dtype=float) - position) * share
    reach = np.asarray(velocity_limits, dtype=float) * dt
    moved = np.clip(position + np.clip(step, -reach, reach), lower, upper)
    return moved, (moved - position) / dt
