"""The joints, poses and controllers of ur_robot_driver's documented interface, as the tests and the arm's soak name them."""

JOINTS = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
          'wrist_3_joint']
# A pose away from singularities (elbow bent, tool down), and one a little off it.
HOME = [0.0, -1.57, 1.57, -1.57, -1.57, 0.0]
AWAY = [0.4, -1.3, 1.2, -1.2, -1.2, 0.6]
COMMANDING = ['scaled_pos_joint_traj_controller', 'pos_joint_traj_controller', 'scaled_vel_joint_traj_controller',
              'vel_joint_traj_controller', 'joint_group_vel_controller', 'forward_joint_traj_controller',
              'forward_cartesian_traj_controller', 'twist_controller', 'pose_based_cartesian_traj_controller',
              'joint_based_cartesian_traj_controller']
HW = '/ur_hardware_interface/'
