"""Transforms from a ROS bag's ``/tf`` and ``/tf_static`` (``tf2_msgs/msg/TFMessage``).

:class:`TfTree` holds every edge of the transform tree (parent → child) over time and composes
the chain from a common frame to a sensor's ``frame_id`` at given stamps, interpolating each
moving edge (scipy's :class:`~scipy.spatial.transform.Slerp` for rotations, linear for
translations). A frame not connected to the common frame, or a moving edge with no transform
within ``max_gap`` of a stamp, is an error naming the frames.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation, Slerp

from softtip.errors import InputError
from softtip.fusion.poses import PoseSeries

__all__ = ["TF_TOPICS", "TfTree", "gravity_orientations", "read_tf"]

TF_TYPE = "tf2_msgs/msg/TFMessage"
#: Topics read, and whether their transforms are static.
TF_TOPICS = {"/tf": False, "/tf_static": True}


@dataclass
class _Edge:
    static: bool
    stamps: list[int] = field(default_factory=list)  # ns
    quats: list[tuple[float, float, float, float]] = field(default_factory=list)  # x, y, z, w
    translations: list[tuple[float, float, float]] = field(default_factory=list)


class TfTree:
    """The transform tree: ``child → (parent, edge)``; each child has one parent."""

    def __init__(self, source: str = "tf"):
        self.source = source
        self._edges: dict[str, tuple[str, _Edge]] = {}

    def add(self, parent: str, child: str, stamp_ns: int, translation, quaternion_xyzw, static: bool) -> None:
        """Add one transform: ``child``'s pose in ``parent`` at ``stamp_ns``."""
        parent, child = parent.lstrip("/"), child.lstrip("/")
        if child in self._edges and self._edges[child][0] != parent:
            raise InputError(
                f"{self.source}: frame {child!r} has two parents, {self._edges[child][0]!r} and {parent!r}; "
                "expected a tree"
            )
        edge = self._edges.setdefault(child, (parent, _Edge(static)))[1]
        edge.static = edge.static or static
        edge.stamps.append(int(stamp_ns))
        edge.quats.append(tuple(float(v) for v in quaternion_xyzw))
        edge.translations.append(tuple(float(v) for v in translation))

    @property
    def frames(self) -> list[str]:
        """Every frame of the tree, sorted."""
        out = set(self._edges)
        out.update(p for p, _ in self._edges.values())
        return sorted(out)

    def _chain(self, frame: str) -> list[str]:
        chain = [frame]
        while chain[-1] in self._edges:
            chain.append(self._edges[chain[-1]][0])
            if len(chain) > len(self._edges) + 1:
                raise InputError(f"{self.source}: the transforms form a cycle through {frame!r}")
        return chain

    def _edge_at(self, child: str, stamps: NDArray[np.int64], max_gap: float) -> tuple[Rotation, NDArray]:
        parent, e = self._edges[child]
        order = np.argsort(e.stamps, kind="stable")
        st = np.asarray(e.stamps, dtype=np.int64)[order]
        q = np.asarray(e.quats)[order]
        tr = np.asarray(e.translations)[order]
        if e.static or len(st) == 1:
            if not e.static:
                far = np.abs(stamps - st[0]) * 1e-9 > max_gap
                if far.any():
                    raise InputError(self._stale(parent, child, stamps[far][0], st))
            k = len(st) - 1  # the latest static transform wins
            return Rotation.from_quat(np.repeat(q[k : k + 1], len(stamps), axis=0)), np.repeat(tr[k : k + 1], len(stamps), axis=0)
        keep = np.concatenate(([True], np.diff(st) > 0))
        st, q, tr = st[keep], q[keep], tr[keep]
        ts = (st - st[0]) * 1e-9
        x = (stamps - st[0]) * 1e-9
        # the nearest transform of each stamp must be within max_gap
        i = np.clip(np.searchsorted(ts, x), 1, len(ts) - 1)
        gap = np.minimum(np.abs(x - ts[i - 1]), np.abs(ts[i] - x))
        far = gap > max_gap
        if far.any():
            raise InputError(self._stale(parent, child, stamps[far][0], st))
        xc = np.clip(x, ts[0], ts[-1])
        rot = Slerp(ts, Rotation.from_quat(q))(xc)
        t = np.stack([np.interp(xc, ts, tr[:, j]) for j in range(3)], axis=-1)
        return rot, t

    def _stale(self, parent: str, child: str, stamp: int, st) -> str:
        return (
            f"{self.source}: no transform {parent!r} → {child!r} within the allowed gap of t = {stamp * 1e-9:.6f} s "
            f"(transforms cover {st[0] * 1e-9:.6f}–{st[-1] * 1e-9:.6f} s): missing or stale"
        )

    def lookup(self, target: str, frame: str, stamps_ns: ArrayLike, max_gap: float = 0.1) -> tuple[Rotation, NDArray]:
        """The pose of ``frame`` in ``target`` at ``stamps_ns`` (int ns, shape (N,)):
        ``(rotation, translation)`` with ``p_target = R p_frame + t``."""
        target, frame = target.lstrip("/"), frame.lstrip("/")
        stamps = np.atleast_1d(np.asarray(stamps_ns, dtype=np.int64))
        up, down = self._chain(frame), self._chain(target)
        common = next((f for f in up if f in down), None)
        if common is None:
            raise InputError(
                f"{self.source}: frame {frame!r} is not connected to {target!r} by the transforms; "
                f"frames present: {', '.join(self.frames) or 'none'}"
            )
        n = len(stamps)
        rot, tr = Rotation.identity(n), np.zeros((n, 3))

        def compose(chain):
            r, t = Rotation.identity(n), np.zeros((n, 3))
            for child in chain[: chain.index(common)]:
                re, te = self._edge_at(child, stamps, max_gap)
                r, t = re * r, re.apply(t) + te  # child pose in its parent, applied after
            return r, t

        r_up, t_up = compose(up)  # frame in common
        r_dn, t_dn = compose(down)  # target in common
        inv = r_dn.inv()
        rot = inv * r_up
        tr = inv.apply(t_up - t_dn)
        return rot, tr

    def orientations(self, world: str, frame: str, stamps_ns: ArrayLike, max_gap: float = 0.1) -> NDArray[np.float64]:
        """``qw, qx, qy, qz`` (N, 4) of ``frame`` in ``world`` at ``stamps_ns``: the sensor's
        orientation for gravity compensation (``world`` with ``z`` up)."""
        rot, _ = self.lookup(world, frame, stamps_ns, max_gap)
        x, y, z, w = rot.as_quat().T
        return np.stack([w, x, y, z], axis=-1)

    def poses(
        self, target: str, frame: str, stamps_ns: ArrayLike, origin_ns: int | None = None, max_gap: float = 0.1
    ) -> PoseSeries:
        """:meth:`lookup` as a :class:`~softtip.fusion.poses.PoseSeries` over the time since
        ``origin_ns`` (s; default the first stamp), at the samples of one sensor (repeated
        stamps collapsed)."""
        stamps = np.asarray(stamps_ns, dtype=np.int64)
        keep = np.concatenate(([True], np.diff(stamps) > 0))
        rot, tr = self.lookup(target, frame, stamps[keep], max_gap)
        origin = int(stamps[0]) if origin_ns is None else int(origin_ns)
        return PoseSeries((stamps[keep] - origin) * 1e-9, rot, tr, max_gap=0.0, name=frame)


def read_tf(path: str | os.PathLike[str], purpose: str = "give the fingertips' poses another way") -> TfTree:
    """Every transform of a bag's ``/tf`` and ``/tf_static`` (``purpose``: what the error of a
    bag without them suggests)."""
    from softtip.io.bag import default_typestore, import_rosbags

    import_rosbags()
    from rosbags.highlevel import AnyReader

    source = os.fspath(path)
    tree = TfTree(source)
    try:
        reader = AnyReader([Path(path)], default_typestore=default_typestore())
        reader.open()
    except Exception as exc:  # rosbags raises several unrelated types for a bad file
        raise InputError(f"{source}: cannot read as a ROS bag ({exc})") from None
    try:
        conns = [c for c in reader.connections if c.topic in TF_TOPICS and c.msgtype == TF_TYPE]
        if not conns:
            raise InputError(f"{source}: no /tf or /tf_static ({TF_TYPE}) topic; {purpose}")
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            for ts in msg.transforms:
                st = ts.header.stamp
                tr, q = ts.transform.translation, ts.transform.rotation
                tree.add(
                    ts.header.frame_id, ts.child_frame_id, st.sec * 1_000_000_000 + st.nanosec,
                    (tr.x, tr.y, tr.z), (q.x, q.y, q.z, q.w), TF_TOPICS[conn.topic],
                )  # fmt: skip
    finally:
        reader.close()
    return tree


def gravity_orientations(
    path: str | os.PathLike[str],
    world: str,
    frame_ids: Sequence[str],
    stamps_ns: ArrayLike,
    frame_id: str | None = None,
    max_gap: float = 0.1,
) -> NDArray[np.float64]:
    """The sensor's orientation in a gravity-aligned frame at each wrench stamp, from a bag's /tf.

    Parameters
    ----------
    path : str or path-like
        The bag.
    world : str
        The gravity frame (``z`` up, e.g. ``world``, ``odom``, ``base_link`` of a fixed base).
    frame_ids : sequence of str
        The distinct ``header.frame_id`` values of the wrench messages (one expected).
    stamps_ns : array-like of int, shape (N,)
        The wrench stamps, ns.
    frame_id : str, optional
        The sensor frame when the messages have none (an empty ``frame_id``).
    max_gap : float
        s; a moving transform farther than this from a stamp is an error.

    Returns
    -------
    (N, 4) ``qw, qx, qy, qz``: the sensor frame in ``world``, as :mod:`softtip.calibration.payload` takes it.

    Raises
    ------
    InputError
        No /tf in the bag, several or no sensor frames, a frame not connected to ``world``, a
        missing or stale transform (naming both frames).
    """
    names = [f for f in frame_ids if f]
    if len(names) > 1:
        raise InputError(
            f"{os.fspath(path)}: the wrench messages have several frame_ids ({', '.join(map(repr, names))}); "
            "expected one sensor frame for --gravity-frame"
        )
    sensor = names[0] if names else frame_id
    if not sensor:
        raise InputError(
            f"{os.fspath(path)}: the wrench messages have an empty header.frame_id; give the sensor frame with --frame-id "
            "to look up its orientation in /tf"
        )
    tree = read_tf(path, purpose=f"--gravity-frame needs the transform {world!r} → {sensor!r}")
    return tree.orientations(world, sensor, stamps_ns, max_gap)
