"""ROS 2 package shell of softtip: the node is :mod:`softtip.ros.node` (``pip install softtip``)."""
