"""Whether numba is loaded in this process: once it is, a compiled loop costs nothing to
start, so the loops that give exactly the same answer as their numpy form
(:func:`.proximity.nearest_samples`, the tangent graph's compiled search) run compiled
at sizes where a process that has not loaded numba keeps to numpy."""

from __future__ import annotations

import sys


def numba_loaded() -> bool:
    """True when some part of this process has imported numba already."""
    return "numba" in sys.modules
