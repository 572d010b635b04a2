"""A survey in flight: what each drone was given, what it has flown, the photos it took,
and the hand-over of a lost drone's unflown lanes. Pure: the hub's survey service feeds it
the vehicles' events and states, stores it (as JSON), and sends the missions it builds.

Progress is known from the autopilots' own reports: a lane is flown once its exit waypoint
is reached (MISSION_ITEM_REACHED) or passed (MISSION_CURRENT beyond it); photos are the
camera's CAMERA_FEEDBACK, each with where it was taken; the area covered is the union of
those photos' footprints, not the lanes.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import shapely
from pydantic import BaseModel, ConfigDict, Field
from shapely import affinity
from shapely.geometry import Polygon, box

from backend.survey.planning.geo import polygon_from_geojson
from backend.survey.planning.schemas import SurveyRequest
from common.geodesy import LocalFrame
from protocol.messages import MissionItem, Photo


class SurveyState(StrEnum):
    PLANNED = "planned"  # missions planned and checked, nothing uploaded
    FLYING = "flying"
    HANDOVER_OFFERED = "handover_offered"  # a drone dropped out; its lanes await a yes
    DONE = "done"  # every lane flown and every drone landed
    ABORTED = "aborted"  # the operator ended it; the drones were sent home
    FAILED = "failed"  # the start did not get every drone going


class DroneState(StrEnum):
    ASSIGNED = "assigned"
    FLYING = "flying"
    DONE = "done"  # its lanes flown, landed
    DROPPED = "dropped"  # out of the survey: failsafe, lost link, low battery or abort


ACTIVE_STATES = frozenset({SurveyState.PLANNED, SurveyState.FLYING, SurveyState.HANDOVER_OFFERED})
# Modes in which a drone has left its mission: a failsafe or a pilot took it home or down.
# (The mission's own RTL item runs in AUTO, so a drone finishing its lanes stays in AUTO.)
# An agent's clock against the hub's: photos are timed by the agent, the survey by the hub.
CLOCK_SLACK_S = 10.0
LEAVING_MODES = frozenset({"RTL", "SMART_RTL", "LAND", "AUTO.RTL", "AUTO.LAND"})


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid")


class LaneRecord(_Model):
    start: tuple[float, float] = Field(description="[lat, lon] where photos start")
    end: tuple[float, float] = Field(description="[lat, lon] where they end")
    entry: int = Field(description="the item number of the lane's entry waypoint")
    exit: int = Field(description="the item number of its exit waypoint")
    done: bool = False


class DroneRun(_Model):
    vehicle_id: str
    state: DroneState = DroneState.ASSIGNED
    items: list[MissionItem]
    lanes: list[LaneRecord]
    # Lanes flown in missions it had before a hand-over replaced them.
    lanes_done_before: int = 0
    photos: list[tuple[float, float]] = Field(default_factory=list, description="[lat, lon]")
    photo_indexes: list[int] = Field(default_factory=list)
    current: int | None = None
    airborne: bool = False
    # Armed since it started flying the survey: a drone that disarms on the ground after
    # (PX4's preflight auto-disarm, a refused take-off) has stopped, though never airborne.
    armed_seen: bool = False
    reason: str | None = None  # why it dropped out
    finished: float | None = None  # Unix time it was seen done or dropped out

    def unflown(self) -> list[LaneRecord]:
        return [lane for lane in self.lanes if not lane.done]


class HandoverOffer(_Model):
    lost: list[str]
    reason: str
    # Per drone still flying: its new mission (from where it is) and that mission's lanes.
    missions: dict[str, list[MissionItem]]
    lanes: dict[str, list[LaneRecord]]
    lanes_moved: int
    total_s: dict[str, float] = Field(description="each drone's estimated time to finish")


class SurveyRun(_Model):
    id: str
    created: float
    started: float | None = None  # Unix time the missions were started
    state: SurveyState = SurveyState.PLANNED
    request: SurveyRequest
    altitude_m: float
    footprint_side_m: float
    footprint_frontal_m: float
    lane_spacing_m: float
    trigger_distance_m: float
    angle_deg: float
    drones: list[DroneRun]
    offer: HandoverOffer | None = None
    handovers: int = 0
    note: str = ""

    def drone(self, vehicle_id: str) -> DroneRun | None:
        return next((d for d in self.drones if d.vehicle_id == vehicle_id), None)

    # -- what the autopilots report ------------------------------------------------------

    def reached(self, vehicle_id: str, item: int) -> bool:
        """MISSION_ITEM_REACHED: lanes whose exit this is (or is before) are flown."""
        return self._flown_up_to(vehicle_id, item)

    def current_item(self, vehicle_id: str, item: int | None) -> bool:
        """MISSION_CURRENT: lanes whose exit lies before the current item are flown."""
        drone = self.drone(vehicle_id)
        if drone is None or item is None or drone.current == item:
            return False
        drone.current = item
        self._flown_up_to(vehicle_id, item - 1)
        return True

    def _flown_up_to(self, vehicle_id: str, item: int) -> bool:
        drone = self.drone(vehicle_id)
        if drone is None or drone.state is not DroneState.FLYING:
            return False
        changed = False
        for lane in drone.lanes:
            if not lane.done and lane.exit <= item:
                lane.done = True
                changed = True
        return changed

    def photo(self, vehicle_id: str, photo: Photo, taken: float | None = None) -> bool:
        """A photo the drone took (at Unix time `taken`, if known). Photos reach the hub
        late after an outage (the agent replays them), perhaps after the drone was seen
        landed: any taken between the start and the drone's end count."""
        drone = self.drone(vehicle_id)
        if drone is None or self.started is None:
            return False
        if taken is not None and (
            taken < self.started - CLOCK_SLACK_S
            or (drone.finished is not None and taken > drone.finished + CLOCK_SLACK_S)
        ):
            return False
        # At-least-once delivery sends the same photo again: the same index at the same
        # place. The same index somewhere else is another photo (a second camera, or a
        # counter that restarted with the autopilot). Newest first: the lists end together.
        position = (photo.lat, photo.lon)
        recent = zip(reversed(drone.photo_indexes[-256:]), reversed(drone.photos), strict=False)
        if any(index == photo.index and tuple(where) == position for index, where in recent):
            return False
        drone.photos.append((photo.lat, photo.lon))
        drone.photo_indexes.append(photo.index)
        return True

    # -- progress --------------------------------------------------------------------------

    def lanes_total(self) -> int:
        # A dropped drone keeps its unflown lanes until they are handed over; then they
        # are the others' and it keeps only the count of those it flew.
        return sum(d.lanes_done_before + len(d.lanes) for d in self.drones)

    def lanes_done(self) -> int:
        return sum(
            d.lanes_done_before + sum(1 for lane in d.lanes if lane.done) for d in self.drones
        )

    def photo_count(self) -> int:
        return sum(len(d.photos) for d in self.drones)

    def orphans(self) -> list[LaneRecord]:
        """The unflown lanes of drones that dropped out, not yet handed over."""
        return [lane for d in self.drones if d.state is DroneState.DROPPED for lane in d.unflown()]


@dataclass(frozen=True, slots=True)
class Geometry:
    """The survey's area and frame, rebuilt from its request (deterministically)."""

    area: Polygon
    frame: LocalFrame


def geometry(run: SurveyRun) -> Geometry:
    area, frame = polygon_from_geojson(run.request.area.model_dump())
    return Geometry(area, frame)


def photo_footprints(run: SurveyRun, geo: Geometry) -> list[Polygon]:
    """Each photo's footprint on the ground: nadir, its long side across the lanes."""
    side, frontal = run.footprint_side_m, run.footprint_frontal_m
    heading = run.angle_deg
    out = []
    for drone in run.drones:
        for lat, lon in drone.photos:
            x, y = geo.frame.to_local(lat, lon)
            rect = box(x - frontal / 2, y - side / 2, x + frontal / 2, y + side / 2)
            out.append(affinity.rotate(rect, heading, origin=(x, y)))
    return out


def covered_fraction(run: SurveyRun, geo: Geometry) -> float:
    shapes = photo_footprints(run, geo)
    if not shapes:
        return 0.0
    return float(geo.area.intersection(shapely.union_all(shapes)).area) / float(geo.area.area)
