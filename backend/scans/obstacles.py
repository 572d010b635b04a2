"""Obstacles as objects that last: each extraction from the point map is matched to the
previous one, so an obstacle keeps its id while it is seen, and its appearing and going
are events (published by the hub, backend/hub/services.py).

Matching is by overlap of the outlines on the ground: a cluster that overlaps a tracked
obstacle is that obstacle, grown or shrunk; one that overlaps none is new; a tracked one
that nothing overlaps any more is gone (its voxels left the bounded map, or a moving
thing left). When two clusters merge, the merged one keeps the first id and the other
goes; when one splits, the first part keeps the id.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from backend.scans.pointmap import MapObstacle


@dataclass(frozen=True)
class ObstacleChanges:
    current: list[MapObstacle]  # with their lasting ids
    appeared: list[MapObstacle]
    gone: list[MapObstacle]


def _overlap(a: MapObstacle, b: MapObstacle) -> bool:
    return (
        a.east_min < b.east_max
        and b.east_min < a.east_max
        and a.north_min < b.north_max
        and b.north_min < a.north_max
    )


class ObstacleTracker:
    def __init__(self) -> None:
        self._tracked: dict[int, MapObstacle] = {}
        self._next_id = 1

    @property
    def current(self) -> list[MapObstacle]:
        return list(self._tracked.values())

    def update(self, found: list[MapObstacle]) -> ObstacleChanges:
        current: list[MapObstacle] = []
        appeared: list[MapObstacle] = []
        taken: set[int] = set()
        for obstacle in found:
            match = next(
                (
                    known_id
                    for known_id, known in self._tracked.items()
                    if known_id not in taken and _overlap(known, obstacle)
                ),
                None,
            )
            if match is None:
                match = self._next_id
                self._next_id += 1
                appeared.append(replace(obstacle, id=match))
            taken.add(match)
            current.append(replace(obstacle, id=match))
        gone = [known for known_id, known in self._tracked.items() if known_id not in taken]
        self._tracked = {obstacle.id: obstacle for obstacle in current}
        return ObstacleChanges(current, appeared, gone)


def describe(obstacle: MapObstacle, change: str) -> str:
    """An event's text: which obstacle, its size and where (site east-north-up)."""
    if change == "gone":
        return f"obstacle {obstacle.id} gone from the point map"
    east = (obstacle.east_min + obstacle.east_max) / 2.0
    north = (obstacle.north_min + obstacle.north_max) / 2.0
    return (
        f"obstacle {obstacle.id} found: {obstacle.east_max - obstacle.east_min:.1f} m x "
        f"{obstacle.north_max - obstacle.north_min:.1f} m, up to {obstacle.up_max:.1f} m, "
        f"centred {east:.1f} m east and {north:.1f} m north of the site origin"
    )
