"""What the tests and benchmarks share, imported as a package wherever the workspace is sourced.

setup.py declares it next to ur3_ft_gripper_description, so catkin's devel
space relays it like the package itself: rostest nodes, the pytest folders and
bench/ import it the same way, with no folder put on sys.path by hand. The
relay puts its parent folder, test/python, on sys.path: that folder holds this
package alone, so no test folder (test/rostest, test/physics...) turns into an
importable name.
"""
