"""A UR arm + Robotiq FT 300 + Robotiq 2F-140.

model: the robot model (xacro expansion and its checks, the TCP, the export).
devices: the simulated FT 300 and 2F-140 on the real drivers' interfaces.
kinematics: forward kinematics of a URDF, which both build on.
"""
