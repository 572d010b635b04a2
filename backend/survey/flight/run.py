"""A survey in flight: what each drone was given, what it has flown, the photos it took,
and the hand-over of a lost drone's unflown lanes. Pure: the hub's survey service feeds it
the vehicles' events and states, stores it (as JSON), and sends the missions it builds.

Progress is known from the autopilots' own reports: a lane is flown once its exit waypoint
is reached (MISSION_ITEM_REACHED) or passed (MISSION_CURRENT beyond it); photos are the
camera's CAMERA_FEEDBACK, each with where it was taken; the area covered is the union of
those photos' footprints, not the lanes.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import shapely
from pydantic import BaseModel, ConfigDict, Field
from shapely import affinity
from shapely.geometry import Polygon, box

from backend.survey.planning.camera import preset
from backend.survey.planning.geo import polygon_from_geojson
from backend.survey.planning.mission import survey_mission
from backend.survey.planning.planner import Lane, LanePlan
from backend.survey.planning.report import DEFAULT_ACCEL_MS2
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


# -- the hand-over -------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Flyer:
    """A drone still flying the survey, in the area's local frame."""

    vehicle_id: str
    position: tuple[float, float]
    home: tuple[float, float]
    # Its own unflown lanes, in order; the first may start where it is (part flown).
    lanes: list[tuple[tuple[float, float], tuple[float, float]]]
    mid_lane: bool


def _time(
    here: tuple[float, float],
    lanes: Sequence[tuple[tuple[float, float], tuple[float, float]]],
    home: tuple[float, float],
    speed: float,
    turnaround: float,
) -> float:
    """Flight time from `here` along the lanes and home, with a stop-and-go per lane end
    (the same model as the plan's report)."""
    distance = 0.0
    for start, end in lanes:
        distance += math.dist(here, start) + math.dist(start, end) + 2 * turnaround
        here = end
    distance += math.dist(here, home)
    return distance / speed + 2 * len(lanes) * speed / DEFAULT_ACCEL_MS2


def _oriented(
    here: tuple[float, float], chunk: Sequence[tuple[tuple[float, float], tuple[float, float]]]
) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """A run of lanes flown back and forth from whichever end of the run is nearer, each
    lane entered at its end nearer the previous one's exit."""
    if not chunk:
        return []
    first, last = chunk[0], chunk[-1]
    near_first = min(math.dist(here, first[0]), math.dist(here, first[1]))
    near_last = min(math.dist(here, last[0]), math.dist(here, last[1]))
    ordered = list(chunk) if near_first <= near_last else list(reversed(chunk))
    out = []
    for a, b in ordered:
        if math.dist(here, b) < math.dist(here, a):
            a, b = b, a
        out.append((a, b))
        here = b
    return out


def split_orphans(
    orphans: Sequence[tuple[tuple[float, float], tuple[float, float]]],
    flyers: Sequence[Flyer],
    speed: float,
    turnaround: float,
) -> dict[str, list[tuple[tuple[float, float], tuple[float, float]]]]:
    """Each flyer's lanes to fly now: its own, then a contiguous run of the lost lanes.

    The lost lanes keep their order (neighbours in the area), are cut into one run per
    flyer, and the cuts and the runs' owners are chosen to make the slowest flyer's time to
    finish (its own lanes, its run, the way home) as short as possible: every cut for up to
    four flyers, by bisection on the target time beyond that."""
    if not flyers:
        raise ValueError("no drone is left to take the lanes")
    n = len(orphans)
    own_end = {f.vehicle_id: (f.lanes[-1][1] if f.lanes else f.position) for f in flyers}

    def finish(f: Flyer, chunk: Sequence[Any]) -> tuple[float, list[Any]]:
        extra = _oriented(own_end[f.vehicle_id], chunk)
        lanes = [*f.lanes, *extra]
        return _time(f.position, lanes, f.home, speed, turnaround), lanes

    best: tuple[float, dict[str, list[Any]]] | None = None
    k = len(flyers)
    orders = (
        itertools.permutations(flyers)
        if k <= 4
        else [sorted(flyers, key=lambda f: min(math.dist(f.position, o[0]) for o in orphans))]
    )
    for order in orders:
        if k <= 4:
            cut_sets: Any = itertools.combinations_with_replacement(range(n + 1), k - 1)
        else:
            cut_sets = [tuple(round(n * (i + 1) / k) for i in range(k - 1))]
        for cuts in cut_sets:
            bounds = [0, *cuts, n]
            worst = 0.0
            plan: dict[str, list[Any]] = {}
            for i, f in enumerate(order):
                t, lanes = finish(f, orphans[bounds[i] : bounds[i + 1]])
                worst = max(worst, t)
                plan[f.vehicle_id] = lanes
                if best is not None and worst >= best[0]:
                    break
            else:
                if best is None or worst < best[0]:
                    best = (worst, plan)
    assert best is not None
    return best[1]


def lane_plan(
    lanes: Sequence[tuple[tuple[float, float], tuple[float, float]]],
    trigger_m: float,
    turnaround_m: float,
    spacing_m: float,
    angle_deg: float,
) -> LanePlan:
    """Lanes given by their ends as a plan: photos every trigger distance, turnarounds
    beyond both ends."""
    out: list[Lane] = []
    path: list[tuple[float, float]] = []
    for start, end in lanes:
        length = math.dist(start, end)
        ux, uy = ((end[0] - start[0]) / length, (end[1] - start[1]) / length) if length else (1, 0)
        shots = max(1, math.ceil(length / trigger_m - 1e-9))
        photos = [
            (start[0] + ux * j * trigger_m, start[1] + uy * j * trigger_m) for j in range(shots)
        ]
        out.append(Lane(start, end, (*photos, end)))
        path += [
            (start[0] - ux * turnaround_m, start[1] - uy * turnaround_m),
            start,
            end,
            (end[0] + ux * turnaround_m, end[1] + uy * turnaround_m),
        ]
    return LanePlan(tuple(out), tuple(path), angle_deg, spacing_m, trigger_m, turnaround_m)


def handover_missions(
    run: SurveyRun,
    geo: Geometry,
    flyers: Sequence[Flyer],
    reason: str,
) -> HandoverOffer:
    """New missions for the drones still flying: each resumes from where it is with its own
    unflown lanes, then takes its share of the lost drones' lanes, then returns home."""
    frame = geo.frame
    orphans = [(frame.to_local(*lane.start), frame.to_local(*lane.end)) for lane in run.orphans()]
    request = run.request
    shares = split_orphans(orphans, flyers, request.speed_ms, request.turnaround_m)
    missions: dict[str, list[MissionItem]] = {}
    lanes: dict[str, list[LaneRecord]] = {}
    total_s: dict[str, float] = {}
    for flyer in flyers:
        share = shares[flyer.vehicle_id]
        plan = lane_plan(
            share, run.trigger_distance_m, request.turnaround_m, run.lane_spacing_m, run.angle_deg
        )
        mission = survey_mission(
            plan,
            frame,
            run.altitude_m,
            speed_ms=request.speed_ms,
            per_photo=not _distance_trigger(request),
            hover=request.hover_and_capture,
            takeoff=None,  # in the air already
            lead_in=not flyer.mid_lane,
        )
        missions[flyer.vehicle_id] = mission.items
        lanes[flyer.vehicle_id] = [
            LaneRecord(
                start=frame.to_geo(*lane.start),
                end=frame.to_geo(*lane.end),
                entry=entry,
                exit=exit_,
            )
            for lane, (entry, exit_) in zip(plan.lanes, mission.lanes, strict=True)
        ]
        total_s[flyer.vehicle_id] = _time(
            flyer.position, share, flyer.home, request.speed_ms, request.turnaround_m
        )
    lost = [d.vehicle_id for d in run.drones if d.state is DroneState.DROPPED and d.unflown()]
    return HandoverOffer(
        lost=lost,
        reason=reason,
        missions=missions,
        lanes=lanes,
        lanes_moved=len(orphans),
        total_s=total_s,
    )


def _distance_trigger(request: SurveyRequest) -> bool:
    camera = request.camera
    return preset(camera).distance_trigger if isinstance(camera, str) else camera.distance_trigger


def flyer_of(
    drone: DroneRun, geo: Geometry, position: tuple[float, float], home: tuple[float, float]
) -> Flyer:
    """A drone still flying, with its own unflown lanes as the hand-over needs them: a lane
    it is part way along (flying to the exit) starts where it is."""
    frame = geo.frame
    lanes: list[tuple[tuple[float, float], tuple[float, float]]] = []
    mid_lane = False
    for lane in drone.unflown():
        start, end = frame.to_local(*lane.start), frame.to_local(*lane.end)
        if not lanes and drone.current is not None and lane.entry < drone.current <= lane.exit:
            start, mid_lane = position, True
        lanes.append((start, end))
    return Flyer(drone.vehicle_id, position, home, lanes, mid_lane)


def accept_offer(run: SurveyRun) -> None:
    """The operator said yes: the drones' lanes become those of their new missions."""
    offer = run.offer
    assert offer is not None
    for drone in run.drones:
        if drone.state is DroneState.DROPPED:
            # Its unflown lanes now belong to others; what it flew still counts.
            drone.lanes_done_before += sum(1 for lane in drone.lanes if lane.done)
            drone.lanes = []
        elif drone.vehicle_id in offer.missions:
            drone.lanes_done_before += sum(1 for lane in drone.lanes if lane.done)
            drone.lanes = offer.lanes[drone.vehicle_id]
            drone.items = offer.missions[drone.vehicle_id]
            drone.current = None
    run.offer = None
    run.handovers += 1
    run.state = SurveyState.FLYING
