# Installed by catkin_python_setup(); do not run directly.
from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(
    packages=['ur3_ft_gripper_description', 'ur3_ft_gripper_description.model',
              'ur3_ft_gripper_description.devices', 'ur3_ft_gripper_description.devices.ur_arm',
              'ur3_ft_gripper_description.devices.physics', 'ur3_ft_gripper_description.urscript',
              # What the tests and bench/ share: relayed into the devel space like the
              # package, so every test and benchmark imports it by name. The relay puts
              # the folder above it on sys.path: test/python holds nothing else.
              'ur3_ft_gripper_testing'],
    package_dir={'': 'src', 'ur3_ft_gripper_testing': 'test/python/ur3_ft_gripper_testing'},
    # The URScript grammar and the manual's function names, read beside the modules.
    package_data={'ur3_ft_gripper_description.urscript': ['grammar.lark', 'manual_functions.txt']},
))
