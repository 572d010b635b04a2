"""The hand-over: a lost drone's unflown lanes split among the drones still flying, each
given a new mission that resumes from where it is, offered to the operator; and the
survey as it is once the operator accepts. Pure, as run.py."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from backend.survey.flight.run import (
    DroneRun,
    DroneState,
    Geometry,
    HandoverOffer,
    LaneRecord,
    SurveyRun,
    SurveyState,
)
from backend.survey.planning.camera import preset
from backend.survey.planning.lanes import Lane, LanePlan
from backend.survey.planning.mission import survey_mission
from backend.survey.planning.report import DEFAULT_ACCEL_MS2
from backend.survey.planning.schemas import SurveyRequest
from protocol.messages import MissionItem


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
