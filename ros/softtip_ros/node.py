"""Entry point ``ros2 run softtip_ros softtip_node``: the node of :mod:`softtip.ros.node`."""

from __future__ import annotations


def main(args: list[str] | None = None) -> None:
    """Run the softtip node (its parameters: ``config/params.yaml``)."""
    try:
        from softtip.ros.node import main as run
    except ImportError as exc:
        raise SystemExit(
            f"softtip_ros needs the softtip Python package in the Python that runs ROS 2 "
            f"(python3 -m pip install softtip; see softtip's docs, the ROS 2 package): {exc}"
        ) from None
    run(args)


if __name__ == "__main__":
    main()
