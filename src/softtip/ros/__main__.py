"""``python -m softtip.ros``: run the softtip ROS 2 node (see :mod:`softtip.ros.node`)."""

from softtip.ros.node import main

if __name__ == "__main__":  # pragma: no cover - needs a ROS 2 installation
    main()
