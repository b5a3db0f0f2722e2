"""Calibration of the fingertip (probing presses, meshes) and of the payload."""

from softtip.calibration.probing import (
    MAX_START_SHIFT,
    PROBING_GUIDE,
    SHAPES,
    Calibration,
    calibrate_fingertip,
    find_presses,
    write_fingertip_toml,
    probing_presses,
    simulate_probing,
)

__all__ = [
    "MAX_START_SHIFT",
    "PROBING_GUIDE",
    "SHAPES",
    "Calibration",
    "calibrate_fingertip",
    "find_presses",
    "write_fingertip_toml",
    "probing_presses",
    "simulate_probing",
]
