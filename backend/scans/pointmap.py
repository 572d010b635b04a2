"""The site's point map: every scan's world points, voxel-downsampled and bounded, and the
obstacles found in it.

A voxel is kept as one integer key (its three indices packed) with the time it was last
seen, in a dict ordered from least to most recently seen: a bounded map forgets the part
of the site nobody has looked at for longest. An hour of scans from a fleet over a static
site costs what the site's surfaces cost, not what the hour does (bench/bench_scans.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]
_BITS = 21
_BIAS = 1 << (_BITS - 1)  # +-1,048,576 voxels each way: 104 km at 10 cm
_MASK = (1 << _BITS) - 1
GROUND_CLEARANCE_M = 0.3  # points lower than this above the site origin are ground
NEIGHBOURS = [(dx, dy) for dx in (-1, 0, 1) for dy in (-1, 0, 1) if dx or dy]


@dataclass(frozen=True)
class MapObstacle:
    """A cluster of occupied cells: its outline's extent on the ground and its height."""

    id: int
    east_min: float
    east_max: float
    north_min: float
    north_max: float
    up_min: float
    up_max: float
    voxels: int


class PointMap:
    def __init__(self, voxel_m: float = 0.1, max_voxels: int = 500_000) -> None:
        self.voxel_m = voxel_m
        self.max_voxels = max_voxels
        self._voxels: dict[int, float] = {}
        self.evicted = 0
        self.version = 0  # counts changes: a reader redraws only a map that changed

    def __len__(self) -> int:
        return len(self._voxels)

    def add(self, enu: Array, time: float) -> None:
        if not len(enu):
            return
        self.version += 1
        cells = np.floor(enu / self.voxel_m).astype(np.int64) + _BIAS
        cells = cells[np.all((cells >= 0) & (cells <= _MASK), axis=1)]
        keys = np.unique((cells[:, 0] << (2 * _BITS)) | (cells[:, 1] << _BITS) | cells[:, 2])
        voxels = self._voxels
        for key in keys.tolist():
            voxels.pop(key, None)  # seen again: to the young end
            voxels[key] = time
        while len(voxels) > self.max_voxels:
            del voxels[next(iter(voxels))]
            self.evicted += 1

    def points(self, limit: int | None = None) -> Array:
        """(n, 3) centres of the occupied voxels, the most recently seen last."""
        keys = np.fromiter(self._voxels.keys(), dtype=np.int64, count=len(self._voxels))
        if limit is not None:
            keys = keys[-limit:]
        cells = np.column_stack(
            [(keys >> (2 * _BITS)) & _MASK, (keys >> _BITS) & _MASK, keys & _MASK]
        )
        return (cells - _BIAS + 0.5) * self.voxel_m

    def obstacles(self, min_voxels: int = 5) -> list[MapObstacle]:
        """Clusters of occupied ground cells (8-connected), ground itself left out."""
        return find_obstacles(self.points(), self.voxel_m, min_voxels)


def find_obstacles(points: Array, voxel_m: float, min_voxels: int = 5) -> list[MapObstacle]:
    """The obstacles of a copy of the map's points (``PointMap.points``): a caller may
    search them off the event loop while the map goes on growing."""
    above = points[points[:, 2] >= GROUND_CLEARANCE_M]
    if not len(above):
        return []
    cells = np.floor(above[:, :2] / voxel_m).astype(np.int64)
    by_cell: dict[tuple[int, int], list[int]] = {}
    for i, (x, y) in enumerate(cells.tolist()):
        by_cell.setdefault((x, y), []).append(i)
    seen: set[tuple[int, int]] = set()
    found: list[MapObstacle] = []
    for cell in by_cell:
        if cell in seen:
            continue
        seen.add(cell)
        stack, members = [cell], []
        while stack:
            x, y = stack.pop()
            members.extend(by_cell[(x, y)])
            for dx, dy in NEIGHBOURS:
                near = (x + dx, y + dy)
                if near in by_cell and near not in seen:
                    seen.add(near)
                    stack.append(near)
        if len(members) < min_voxels:
            continue
        group = above[members]
        low, high = group.min(axis=0), group.max(axis=0)
        half = voxel_m / 2.0
        found.append(
            MapObstacle(
                len(found) + 1,
                float(low[0] - half),
                float(high[0] + half),
                float(low[1] - half),
                float(high[1] + half),
                float(low[2] - half),
                float(high[2] + half),
                len(members),
            )
        )
    return found
