"""What the leader's LIDAR has seen, as a follower keeps it: the scans' returns the hub
relays (`protocol.messages.LeaderScan`), in the formation's frame, one point per cell.

A 2-D LIDAR says nothing of height, so each point stands for an obstacle from the ground
up: a follower flying lower than the leader is as blocked by it. The map is a dict of
cells (plain Python: the agent runs on a Pi Zero and imports no numpy for this), bounded,
the oldest cell dropped first; a query looks at the cells within the clearance only, so
its cost does not grow with the map.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

CELL_M = 0.2  # one point kept per cell this wide: finer than any clearance worth flying
MAX_CELLS = 20_000  # about 1,000 m of wall at 0.2 m, 0.5 MB of tuples


class ScanObstacles:
    def __init__(self, cell_m: float = CELL_M, max_cells: int = MAX_CELLS) -> None:
        self.cell_m = cell_m
        self.max_cells = max_cells
        self._cells: dict[tuple[int, int], tuple[float, float]] = {}
        self.scans = 0  # scans taken in
        self.last_seq: int | None = None

    def __len__(self) -> int:
        return len(self._cells)

    def add(self, north: Sequence[float], east: Sequence[float], seq: int | None = None) -> None:
        """One scan's returns (metres north and east); the newest point of a cell wins and
        the cell becomes the newest, so what the leader still sees is kept longest."""
        for n, e in zip(north, east, strict=True):
            key = (math.floor(n / self.cell_m), math.floor(e / self.cell_m))
            self._cells.pop(key, None)
            self._cells[key] = (n, e)
        while len(self._cells) > self.max_cells:
            del self._cells[next(iter(self._cells))]
        self.scans += 1
        self.last_seq = seq

    def nearest(
        self, north: float, east: float, within_m: float
    ) -> tuple[float, tuple[float, float]] | None:
        """The closest point within ``within_m`` (horizontally) of (north, east) and its
        distance, or None when the place is clear."""
        if not self._cells:
            return None
        reach = math.ceil(within_m / self.cell_m)
        cn, ce = math.floor(north / self.cell_m), math.floor(east / self.cell_m)
        best: tuple[float, tuple[float, float]] | None = None
        for i in range(cn - reach, cn + reach + 1):
            for j in range(ce - reach, ce + reach + 1):
                point = self._cells.get((i, j))
                if point is None:
                    continue
                d = math.hypot(point[0] - north, point[1] - east)
                if d <= within_m and (best is None or d < best[0]):
                    best = (d, point)
        return best
