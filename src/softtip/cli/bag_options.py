"""Command-line options shared by the commands that write bags (``estimate``, ``fuse``).

:func:`bag_output_options` adds ``--to-bag``, ``--ros-distro`` and ``--frame-id``;
:func:`output_frame_id` chooses the ``frame_id`` of the messages.
"""

from __future__ import annotations

import click

from softtip.ros import DEFAULT_FRAME_ID
from softtip.ros.bagout import DEFAULT_DISTRO, DISTROS

__all__ = ["bag_output_options", "output_frame_id"]


def bag_output_options(frame_default: str = f"a bag input's own, else {DEFAULT_FRAME_ID}"):
    """A decorator adding ``--to-bag PATH``, ``--ros-distro NAME`` and ``--frame-id FRAME``
    (keyword arguments ``to_bag``, ``ros_distro``, ``frame_id``; ``None`` when not given);
    ``frame_default`` says in ``--help`` what the frame is without ``--frame-id``."""
    options = [
        click.option(
            "--to-bag",
            "to_bag",
            type=click.Path(),
            metavar="PATH",
            help="Also write the results as a ROS bag: a rosbag2 directory in the format of --ros-distro, "
            "or a ROS 1 bag for a name ending in .bag. PATH must not exist.",
        ),
        click.option(
            "--ros-distro",
            type=click.Choice(list(DISTROS)),
            default=None,
            help=f"The ROS distribution that will play the --to-bag output: humble (rosbag2 metadata version 5, "
            f"sqlite3), iron (7, MCAP), jazzy and rolling (9, MCAP), noetic (ROS 1 .bag).  [default: {DEFAULT_DISTRO}; "
            "noetic for a name ending in .bag]",
        ),
        click.option(
            "--frame-id",
            metavar="FRAME",
            default=None,
            help=f"header.frame_id of every message in the --to-bag output.  [default: {frame_default}]",
        ),
    ]

    def decorate(f):
        for option in reversed(options):
            f = option(f)
        return f

    return decorate


def output_frame_id(frame_id: str | None, input_frame_id: str = "") -> str:
    """The ``frame_id`` of the output messages: the one given, else the input's, else
    ``ft_sensor`` (RViz needs a frame to draw in)."""
    if frame_id is not None:
        if not frame_id.strip():
            raise click.BadParameter("expected a frame name, not an empty one", param_hint="--frame-id")
        return frame_id
    return input_frame_id or DEFAULT_FRAME_ID
