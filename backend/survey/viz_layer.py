"""A survey's planned lanes in the 3D view while it is flown.

Each drone's lanes, as the survey holds them now (an accepted hand-over moves a dropped
drone's unflown lanes to the others), are drawn as line segments at the survey's
altitude above that drone's home, in the drone's colour. The survey's progress messages
on the bus (``Topic.SURVEYS``, the 2D map's ``survey`` messages) say when to redraw; a
survey that is done, aborted or failed is taken out of the scene.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import viser

from backend.errors import NotFound
from backend.realtime.bus import Bus, LatestSubscription, Topic
from backend.survey.flight.run import SurveyRun, SurveyState
from backend.survey.service import SurveyService
from backend.viz3d.colours import rgb, vehicle_colour
from backend.viz3d.frame import HomeAltitude
from backend.viz3d.scene import SURVEY_LANES, FleetScene
from protocol.messages import SurveyUpdate

# Drawn while its drones fly it; a planned survey is still a preview on the map.
FLOWN_STATES = frozenset({SurveyState.FLYING, SurveyState.HANDOVER_OFFERED})
LatLon = tuple[float, float]
_Drawn = tuple[npt.NDArray[np.float32], viser.LineSegmentsHandle]


@dataclass(frozen=True)
class PlannedLanes:
    """What the layer draws of a survey, copied on the hub's event loop (which changes
    the survey) so that drawing it in a worker thread reads nothing that moves."""

    survey_id: str
    flown: bool
    altitude_m: float  # above each drone's home
    lanes: dict[str, list[tuple[LatLon, LatLon]]]  # vehicle id -> [(start, end)]

    @classmethod
    def of(cls, run: SurveyRun) -> PlannedLanes:
        return cls(
            survey_id=run.id,
            flown=run.state in FLOWN_STATES,
            altitude_m=run.altitude_m,
            lanes={d.vehicle_id: [(lane.start, lane.end) for lane in d.lanes] for d in run.drones},
        )


class SurveyLanes:
    def __init__(self, scene: FleetScene, home_alt: HomeAltitude) -> None:
        self.scene = scene
        self.home_alt = home_alt
        # survey id -> vehicle id -> its drawn lanes (n, 2, 3) and their node
        self._drawn: dict[str, dict[str, _Drawn]] = {}
        # survey id -> the frame its lanes hang under: removing it removes them all
        self._roots: dict[str, viser.FrameHandle] = {}

    def show(self, planned: PlannedLanes) -> None:
        """Draw the survey's lanes, or take them out once it is no longer flown. Lanes
        that have not changed are not sent again (progress comes every second)."""
        with self.scene.batch():
            if not planned.flown:
                self._remove(planned.survey_id)
                return
            root = f"/{SURVEY_LANES.key}/{planned.survey_id}"
            if planned.survey_id not in self._roots:
                self._roots[planned.survey_id] = self.scene.server.scene.add_frame(
                    root, show_axes=False
                )
            drawn = self._drawn.setdefault(planned.survey_id, {})
            for vehicle_id, lanes in planned.lanes.items():
                segments = self._segments(vehicle_id, lanes, planned.altitude_m)
                old = drawn.get(vehicle_id)
                if old is not None and np.array_equal(old[0], segments):
                    continue
                if old is not None:
                    old[1].remove()
                    del drawn[vehicle_id]
                if not len(segments):
                    continue  # its lanes moved to others (or none placed yet)
                drawn[vehicle_id] = (
                    segments,
                    self.scene.server.scene.add_line_segments(
                        f"{root}/{vehicle_id}",
                        segments,
                        colors=rgb(vehicle_colour(vehicle_id)),
                        thickness=3.0,
                        thickness_units="screen",
                    ),
                )
                self.scene.show_layer(SURVEY_LANES)

    @property
    def surveys(self) -> list[str]:
        return list(self._drawn)

    def _remove(self, survey_id: str) -> None:
        self._drawn.pop(survey_id, None)
        if (root := self._roots.pop(survey_id, None)) is not None:
            root.remove()

    def _segments(
        self, vehicle_id: str, lanes: list[tuple[LatLon, LatLon]], altitude_m: float
    ) -> npt.NDArray[np.float32]:
        frame = self.scene.frame
        ground = frame.ground(self.home_alt(vehicle_id))
        placed: list[tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]] = []
        if ground is not None:
            for (lat0, lon0), (lat1, lon1) in lanes:
                start = frame.place(lat0, lon0, ground + altitude_m)
                end = frame.place(lat1, lon1, ground + altitude_m)
                if start is not None and end is not None:
                    placed.append((start, end))
        return np.array(placed, dtype=np.float32).reshape(-1, 2, 3)

    async def follow(self, bus: Bus, surveys: SurveyService, interval_s: float) -> None:
        """Keep the layer in step with the surveys, at most once per ``interval_s``."""
        updates = LatestSubscription()
        bus.subscribe(Topic.SURVEYS, updates)  # before reading, so no change falls between
        try:
            current = [PlannedLanes.of(run) for run in surveys.active()]
            while True:
                await asyncio.to_thread(self._show_all, current)
                await asyncio.sleep(interval_s)  # pacing: updates meanwhile coalesce
                batch: list[SurveyUpdate] = await updates.drain()
                current = []
                for update in batch:
                    try:
                        current.append(PlannedLanes.of(surveys.get(update.survey_id)))
                    except NotFound:  # not this hub's to follow (any more)
                        current.append(PlannedLanes(update.survey_id, False, 0.0, {}))
        finally:
            bus.unsubscribe(Topic.SURVEYS, updates)

    def _show_all(self, planned: list[PlannedLanes]) -> None:
        with self.scene.batch():
            for one in planned:
                self.show(one)
