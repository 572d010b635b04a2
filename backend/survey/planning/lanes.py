"""A lane plan as data: the fleet's common grid, each lane with its photos, and the path
that flies them (planner.py lays them out)."""

from __future__ import annotations

import math
from dataclasses import dataclass

Point = tuple[float, float]


@dataclass(frozen=True, slots=True)
class Grid:
    """A fleet's common lane grid: lanes at y0 + k * spacing and photos at x0 + j * trigger
    distance, in the frame rotated by the grid angle about (cx, cy)."""

    cx: float
    cy: float
    x0: float
    y0: float


@dataclass(frozen=True, slots=True)
class Lane:
    """One lane in the local frame: photos are taken from start to end."""

    start: tuple[float, float]
    end: tuple[float, float]
    photos: tuple[tuple[float, float], ...]

    @property
    def length_m(self) -> float:
        return math.dist(self.start, self.end)


@dataclass(frozen=True, slots=True)
class LanePlan:
    lanes: tuple[Lane, ...]
    path: tuple[tuple[float, float], ...]  # turnaround-in, start, end, turnaround-out per lane
    angle_deg: float
    lane_spacing_m: float
    trigger_distance_m: float
    turnaround_m: float

    @property
    def path_length_m(self) -> float:
        return sum(math.dist(a, b) for a, b in zip(self.path, self.path[1:], strict=False))

    @property
    def photo_count(self) -> int:
        return sum(len(lane.photos) for lane in self.lanes)
