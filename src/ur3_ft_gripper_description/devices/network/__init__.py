"""The simulated devices' network faces: the vendors' own wire protocols on TCP sockets, no ROS.

Each face is a thin server over a callable of the device's core; the node
that hosts the core starts it (see listen.py for the address rules).
"""
