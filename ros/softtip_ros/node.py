"""Entry point ``ros2 run softtip_ros softtip_node``: the node of :mod:`softtip.ros.node`."""

from __future__ import annotations


def main(args: list[str] | None = None) -> None:
    """Run the softtip node (its parameters: ``config/params.yaml``)."""
    from softtip.ros.node import main as run

    run(args)


if __name__ == "__main__":
    main()
