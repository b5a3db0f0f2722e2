"""The float back end :data:`softtip.core._xp.PY` as a module, for the kernels a compiled step
function calls (:mod:`softtip.core._jit`): numba resolves a module's attributes, not a
namespace object's. The same functions as ``PY``, so a step gives the same bits compiled and
as Python. ``pow`` is left out on purpose: ``PY.pow`` is numpy's power, which compiled code
cannot call (numba's is the C library's, which differs in the last bit): a kernel that needs
it runs before or after the step.
"""

from __future__ import annotations

import math

from softtip.core._xp import _py_and as logical_and
from softtip.core._xp import _py_div as div
from softtip.core._xp import _py_not as logical_not
from softtip.core._xp import _py_or as logical_or
from softtip.core._xp import _py_sqrt as sqrt
from softtip.core._xp import _py_where as where

__all__ = [
    "sqrt", "div", "where", "atan2", "abs", "maximum", "isfinite", "logical_and", "logical_or", "logical_not", "nan",
]  # fmt: skip

atan2 = math.atan2
abs = abs  # noqa: A001 - the back ends' name for it
maximum = max
isfinite = math.isfinite
nan = math.nan
