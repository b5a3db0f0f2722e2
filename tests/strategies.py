"""Hypothesis strategies: synthetic soft-finger contacts on each fingertip shape."""

import numpy as np
from hypothesis import strategies as st

from softtip import Capsule, Ellipsoid, Sphere

unit = st.floats(-1.0, 1.0, allow_nan=False)


@st.composite
def unit_vectors(draw, upper=False):
    v = np.array([draw(st.floats(-1, 1)), draw(st.floats(-1, 1)), draw(st.floats(-1, 1))])
    n = np.linalg.norm(v)
    if n < 1e-3:
        v, n = np.array([0.0, 0.0, 1.0]), 1.0
    v = v / n
    if upper:
        v[2] = abs(v[2])
    return v


@st.composite
def surface_points(draw, tip):
    """A point on the skin (and its normal) that a finger can be touched at."""
    if isinstance(tip, Capsule):
        if draw(st.booleans()):
            u = draw(unit_vectors(upper=True))
            r = np.array([0.0, 0.0, tip.length]) + tip.radius * u
        else:
            phi = draw(st.floats(-np.pi, np.pi))
            z = draw(st.floats(0.0, tip.length))
            r = np.array([tip.radius * np.cos(phi), tip.radius * np.sin(phi), z])
    elif isinstance(tip, Sphere):
        r = np.array(tip.center) + tip.radius * draw(unit_vectors())
    elif isinstance(tip, Ellipsoid):
        r = np.array(tip.center) + np.array(tip.semi_axes) * draw(unit_vectors())
    else:
        raise TypeError(tip)
    return r, tip.normal(r)


@st.composite
def soft_contacts(draw, tip):
    """(r, n, f, sigma) with f pushing into the skin at r."""
    r, n = draw(surface_points(tip))
    push = draw(st.floats(0.05, 20.0))
    t = np.cross(n, draw(unit_vectors()))
    tn = np.linalg.norm(t)
    t = t / tn if tn > 1e-6 else np.zeros(3)
    f = -push * n + draw(st.floats(0.0, 1.0)) * push * t
    sigma = draw(st.floats(-5e-3, 5e-3))
    return r, n, f, sigma


TIPS = [
    Sphere(0.016, center=(0.001, -0.002, 0.03)),
    Capsule(0.016, 0.020),
    Ellipsoid((0.012, 0.016, 0.022), center=(0.0, 0.001, 0.01)),
]
