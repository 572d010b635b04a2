"""Holes (no-fly areas) against straight transits: which would fly into one. The planner
orders lanes to avoid them and the path bound (bound.py) counts them."""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry


def crossings(
    froms: np.ndarray, tos: np.ndarray, holes: BaseGeometry, *, pairwise: bool = False
) -> np.ndarray:
    """Which straight transits from each of `froms` to each of `tos` ((n, 2) arrays) would
    fly into a hole, not merely touch its edge, where a lane may end: (n_from, n_to), or
    with `pairwise` from each of `froms` to the same row of `tos`: (n,)."""
    if not pairwise and froms is tos:  # a transit crosses a hole either way: test once
        i, j = np.triu_indices(len(froms), 1)
        both = np.zeros((len(froms), len(froms)), dtype=bool)
        both[i, j] = crossings(froms[i], froms[j], holes, pairwise=True)
        return both | both.T
    if pairwise:
        pairs = np.stack([froms, tos], axis=1)
    else:
        pairs = np.stack(np.broadcast_arrays(froms[:, None, :], tos[None, :, :]), axis=2)
        pairs = pairs.reshape(-1, 2, 2)
    inner = holes.buffer(-0.01)
    shapely.prepare(inner)
    # Only a transit whose box meets a hole's box can cross it: test those alone.
    lo, hi = pairs.min(axis=1), pairs.max(axis=1)
    near = np.zeros(len(pairs), dtype=bool)
    for part in getattr(inner, "geoms", [inner]):
        x0, y0, x1, y1 = part.bounds
        near |= (lo[:, 0] <= x1) & (hi[:, 0] >= x0) & (lo[:, 1] <= y1) & (hi[:, 1] >= y0)
    hit = np.zeros(len(pairs), dtype=bool)
    hit[near] = shapely.intersects(shapely.linestrings(pairs[near]), inner)
    return hit if pairwise else hit.reshape(len(froms), len(tos))
