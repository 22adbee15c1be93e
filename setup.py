# Installed by catkin_python_setup(); do not run directly.
from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(
    packages=['ur3_ft_gripper_description', 'ur3_ft_gripper_description.model',
              'ur3_ft_gripper_description.devices', 'ur3_ft_gripper_description.devices.ur_arm',
              'ur3_ft_gripper_description.devices.physics'],
    package_dir={'': 'src'},
))
