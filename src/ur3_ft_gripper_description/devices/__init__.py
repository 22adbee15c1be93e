"""The simulated FT 300 and 2F-140 on the real drivers' interfaces, and gripper_joint_states."""
