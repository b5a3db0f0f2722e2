"""Several fingertips in a common frame: their poses and the grasped object.

:mod:`~softtip.fusion.poses` (a sensor frame's pose over time; hand files; pose columns),
:mod:`~softtip.fusion.tf` (poses from a bag's ``/tf``), :mod:`~softtip.fusion.fuse` (two
contacts read as the object's local geometry), :mod:`~softtip.fusion.viz` (the Rerun view of
a fused grasp, ``rerun-sdk`` needed). :func:`fuse_logs` runs the estimator on each
fingertip's log and fuses the results.
"""

from __future__ import annotations

from collections.abc import Sequence

from numpy.typing import ArrayLike

from softtip.core.fingertip import Fingertip, load_fingertip
from softtip.estimator import EstimatorConfig, estimate
from softtip.estimator.tare import noise_in_use
from softtip.fusion.fuse import GRASPS, Finger, FusedGrasp, fuse
from softtip.fusion.poses import POSE_COLUMNS, HandFile, PoseSeries, poses_from_columns, read_hand_file

__all__ = [
    "GRASPS",
    "POSE_COLUMNS",
    "Finger",
    "FusedGrasp",
    "HandFile",
    "PoseSeries",
    "fuse",
    "fuse_logs",
    "poses_from_columns",
    "read_hand_file",
]


def fuse_logs(
    logs: Sequence[tuple[str, ArrayLike, ArrayLike, PoseSeries]],
    tip: Fingertip | str | Sequence[Fingertip | str] = "murakami2006",
    config: EstimatorConfig | None = None,
    **fuse_options,
) -> tuple[FusedGrasp, list[Finger]]:
    """Estimate each fingertip's log and fuse the two.

    Parameters
    ----------
    logs : two (name, t, wrench, pose)
        Each fingertip's raw log (``t`` s on a clock common to both, ``wrench`` (N, 6) N and
        N·m in its sensor frame) and its sensor frame's pose in the common frame.
    tip : Fingertip, preset, TOML path, or one per log
    config : EstimatorConfig, optional
        The estimator's settings (the same for both).
    **fuse_options
        :func:`~softtip.fusion.fuse.fuse` options (``object_mass``, ``gravity``, ...).

    Returns
    -------
    (FusedGrasp, [Finger, Finger])
    """
    tips = list(tip) if isinstance(tip, (list, tuple)) else [tip] * len(logs)
    config = config or EstimatorConfig()
    fingers = []
    for (name, t, w, pose), tp in zip(logs, tips):
        est = estimate(t, w, load_fingertip(tp), config)
        fingers.append(Finger(name, est, pose, noise_in_use(config, est.tare)))  # measured with noise_from_tare
    return fuse(fingers, **fuse_options), fingers
