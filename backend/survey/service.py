"""Area surveys (issue 17): what the operators ask of them. Preview (plan, split, check;
nothing kept), create (every part checked by the safety rails before anything is kept),
start (every mission uploaded, then all started together), accept a hand-over, take a
drone out, abort; and the survey's areas from other tools' files, and its missions as
files for them.

The planning is pure (backend.survey.planning) and runs in worker processes
(plan_workers.py); following the drones once they fly is tracker.py's; each command goes
through the operators' own command path (launch.py).
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict
from typing import Any, Literal

from backend.auth.policy import Principal
from backend.auth.rate_limit import Limit, RateLimiter
from backend.errors import Conflict, InvalidRequest, NotFound, RequestTooLarge, SafetyViolation
from backend.fleet.collaborators import CommandServices
from backend.fleet.registry import VehicleRecord
from backend.realtime.bus import Bus
from backend.safety.mission_schemas import Mission, MissionCheckResponse
from backend.safety.snapshot import home, position, snapshot_of
from backend.settings import HubSettings
from backend.survey.files.areas import mission_path_geojson
from backend.survey.files.qgc_plan import to_qgc_plan
from backend.survey.files.wpl import to_wpl
from backend.survey.fleet_cameras import camera_violations, carried_cameras
from backend.survey.flight.handover import accept_offer
from backend.survey.flight.progress import new_run
from backend.survey.flight.run import ACTIVE_STATES, DroneState, SurveyRun, SurveyState
from backend.survey.launch import SurveyCommands
from backend.survey.plan_workers import ClientWatch, SurveyPlanner
from backend.survey.planning.schemas import SurveyPart, SurveyPreview, SurveyRequest
from backend.survey.planning.survey import Fleet, percent
from backend.survey.repository import SurveyRepository
from backend.survey.tracker import SurveyTracker
from protocol.messages import MissionSetCurrentCommand, MissionUploadCommand, ReturnToLaunchCommand

MissionFormat = Literal["plan", "wpl", "geojson"]


class SurveyService(SurveyTracker):
    def __init__(
        self,
        hub: CommandServices,
        bus: Bus,
        repository: SurveyRepository,
        settings: HubSettings,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        super().__init__(hub, bus, repository, settings, clock)
        self._commands = SurveyCommands(hub)
        # Plans off the event loop, bounded (plan_workers.py); the preview plans here too.
        self.planner = SurveyPlanner(settings)
        # Area files (KML, GeoJSON, .plan) each user may import, parsed in the planner's
        # import worker.
        self.import_limiter = RateLimiter(Limit(settings.survey_imports_per_minute, 60.0))

    async def run(self) -> None:
        try:
            await super().run()
        finally:
            self.planner.close()  # every worker killed: their plans end as 503s

    async def preview(
        self, request: SurveyRequest, gone: ClientWatch | None = None
    ) -> SurveyPreview:
        """The plan split across the chosen drones, each part's mission checked by the
        safety rails; nothing is kept or uploaded. `gone` as for `create`."""
        records = self._chosen(request.vehicle_ids)
        survey = await self.planner.plan(request, _fleet(records), gone)
        cameras = camera_violations(request.camera, carried_cameras(records))
        parts = []
        for part in survey.parts:
            record = records[part.vehicle_id]
            check = await asyncio.to_thread(self._hub.safety.check_mission, record, part.items)
            camera = [cameras[record.id]] if record.id in cameras else []
            parts.append(
                SurveyPart(
                    vehicle_id=part.vehicle_id,
                    mission=Mission(items=part.items),
                    lanes=len(part.lane_paths),
                    photo_count=part.photo_count,
                    path_length_m=part.path_length_m,
                    transit_s=part.transit_s,
                    survey_s=part.survey_s,
                    home_s=part.home_s,
                    total_s=part.total_s,
                    lane_paths=part.lane_paths,
                    check=MissionCheckResponse.build([*check.violations, *camera], check.estimate),
                )
            )
        calc = survey.calc
        return SurveyPreview(
            ok=all(part.check.ok for part in parts),
            altitude_m=calc.altitude_m,
            gsd_cm=calc.gsd_cm,
            footprint_side_m=calc.footprint_side_m,
            footprint_frontal_m=calc.footprint_frontal_m,
            lane_spacing_m=calc.lane_spacing_m,
            trigger_distance_m=calc.trigger_distance_m,
            angle_deg=survey.angle_deg,
            area_m2=survey.area_m2,
            coverage_pct=percent(survey.coverage),
            coverage_at_overlaps_pct=percent(survey.coverage_at_overlaps),
            photo_count=sum(part.photo_count for part in parts),
            lanes=sum(part.lanes for part in parts),
            parts=parts,
        )

    # -- operator actions ----------------------------------------------------------------

    async def create(
        self,
        request: SurveyRequest,
        principal: Principal,
        gone: ClientWatch | None = None,
    ) -> SurveyRun:
        """Plan, split and check; nothing is uploaded. Every drone must be known,
        connected, ready, on the ground and in no other survey, and every part's mission
        must pass the safety rails. `gone` finishes if the client goes away: the plan
        stops."""
        records = self._chosen(request.vehicle_ids)
        busy = self._busy_vehicles()
        for vid, record in records.items():
            if not record.connected:
                raise InvalidRequest("vehicle_ids", f"vehicle {vid} is not connected")
            if vid in busy:
                raise InvalidRequest("vehicle_ids", f"vehicle {vid} is busy in survey {busy[vid]}")
            state = record.state
            if state is not None and (state.armed or state.landed_state not in (None, "on_ground")):
                raise InvalidRequest(
                    "vehicle_ids", f"vehicle {vid} is busy: it is flying; land it first"
                )
            if state is not None and state.ready_to_fly is False:
                raise InvalidRequest(
                    "vehicle_ids",
                    f"vehicle {vid} is not ready: {state.not_ready_reason or 'pre-arm checks'}",
                )
        survey = await self.planner.plan(request, _fleet(records), gone)
        # Before take-off, not at upload: a drone whose camera is not the plan's.
        cameras = camera_violations(request.camera, carried_cameras(records))
        violations: list[dict[str, object]] = [
            {**asdict(violation), "vehicle_id": vid} for vid, violation in cameras.items()
        ]
        for part in survey.parts:
            record = records[part.vehicle_id]
            check = await asyncio.to_thread(self._hub.safety.check_mission, record, part.items)
            for violation in check.violations:
                violations.append({**asdict(violation), "vehicle_id": record.id})
        if violations:
            # No drone gets a mission unless every part passes.
            raise SafetyViolation(violations)
        run = new_run(request, survey)
        await self._drives(run.id)  # a new id: nobody else can hold it
        async with self._lock:
            self._runs[run.id] = run
            self._owners[run.id] = principal.name
            await self._save(run)
        return run

    async def start(self, survey_id: str, principal: Principal) -> SurveyRun:
        """Upload every drone's mission, then start them all together (`SurveyCommands.launch`). An
        upload refused anywhere starts nothing."""
        run = self.get(survey_id)
        if run.state is not SurveyState.PLANNED:
            raise Conflict(f"survey {survey_id} is {run.state}; only a planned one can start")
        # An agent may have come back with another camera since the survey was created.
        chosen = {d.vehicle_id: self._hub.registry.get(d.vehicle_id) for d in run.drones}
        if cameras := camera_violations(run.request.camera, carried_cameras(chosen)):
            reasons = "; ".join(violation.message for violation in cameras.values())
            raise Conflict(f"survey {survey_id} not started: {reasons}")
        uploads = await asyncio.gather(
            *(
                self._commands.send(principal, d.vehicle_id, MissionUploadCommand(items=d.items))
                for d in run.drones
            )
        )
        refused = [
            f"{d.vehicle_id}: {why}" for d, why in zip(run.drones, uploads, strict=True) if why
        ]
        if refused:
            async with self._lock:
                run.state = SurveyState.FAILED
                run.note = "upload refused: " + "; ".join(refused)
                await self._save(run)
            raise Conflict(f"survey {survey_id} not started: {run.note}")
        async with self._lock:
            run.state = SurveyState.FLYING
            run.started = time.time()
            await self._save(run)
        started = await asyncio.gather(
            *(self._commands.launch(principal, run, d) for d in run.drones)
        )
        async with self._lock:
            for drone, why in zip(run.drones, started, strict=True):
                if why is None:
                    drone.state = DroneState.FLYING
                else:
                    self._drop(run, drone, f"did not start: {why}")
            if all(d.state is DroneState.DROPPED for d in run.drones):
                run.state = SurveyState.FAILED
                run.note = "no drone started"
            await self._save(run)
        return run

    async def accept(self, survey_id: str, principal: Principal) -> SurveyRun:
        """Upload the offered missions; each drone flies on from where it is."""
        run = self.get(survey_id)
        if run.state is not SurveyState.HANDOVER_OFFERED or run.offer is None:
            raise Conflict(f"survey {survey_id} has no hand-over on offer")
        async with self._lock:
            # Planned again from where the drones are now: they flew on while it waited.
            self._offer(run, run.offer.reason)
        offer = run.offer
        if offer is None:
            raise Conflict(f"survey {survey_id}: {run.note or 'no drone can take the lanes'}")
        uploads = await asyncio.gather(
            *(
                self._commands.send(principal, vid, MissionUploadCommand(items=items))
                for vid, items in offer.missions.items()
            )
        )
        refused = [f"{vid}: {why}" for vid, why in zip(offer.missions, uploads, strict=True) if why]
        if refused:
            raise Conflict("hand-over not made: " + "; ".join(refused))
        async with self._lock:
            accept_offer(run)
            await self._save(run)
        # Fly the new missions from their first item at once (MISSION_SET_CURRENT: a
        # running mission jumps there), not after the item in flight.
        await asyncio.gather(
            *(
                self._commands.send(principal, vid, MissionSetCurrentCommand(seq=1))
                for vid in offer.missions
            )
        )
        return run

    async def abort(self, survey_id: str, principal: Principal) -> SurveyRun:
        """End the survey: every drone still out is sent home (RTL)."""
        run = self.get(survey_id)
        if run.state not in ACTIVE_STATES:
            raise Conflict(f"survey {survey_id} is {run.state} already")
        async with self._lock:
            run.state = SurveyState.ABORTED
            run.offer = None
            await self._save(run)
        flying = [d.vehicle_id for d in run.drones if d.state is DroneState.FLYING]
        await asyncio.gather(
            *(self._commands.send(principal, v, ReturnToLaunchCommand()) for v in flying)
        )
        return run

    async def drop_vehicle(
        self, survey_id: str, vehicle_id: str, principal: Principal
    ) -> SurveyRun:
        """The operator takes one drone out: it returns home, its lanes are offered."""
        run = self.get(survey_id)
        drone = run.drone(vehicle_id)
        if drone is None:
            raise NotFound(f"vehicle {vehicle_id} is not in survey {survey_id}")
        if run.state not in ACTIVE_STATES or drone.state is not DroneState.FLYING:
            raise Conflict(f"vehicle {vehicle_id} is not flying survey {survey_id}")
        await self._commands.send(principal, vehicle_id, ReturnToLaunchCommand())
        async with self._lock:
            self._drop(run, drone, f"taken out by {principal.name}")
            await self._save(run)
        return run

    # -- files ---------------------------------------------------------------------------

    async def import_area(self, principal: Principal, kind: str, content: str) -> bytes:
        """A survey request's fields from another tool's file, as JSON: bounded per user
        (`survey_imports_per_minute`: every attempt counts, a bad file is parsed too) and
        in size, and parsed in a worker process, never on the event loop."""
        self.import_limiter.check(principal.name, "survey imports")
        self.import_limiter.hit(principal.name)
        size, limit = len(content.encode()), self._settings.survey_import_max_bytes
        if size > limit:
            raise RequestTooLarge(
                f"the file is {size:,} bytes; the limit is {limit:,} (survey_import_max_bytes)"
            )
        return await self.planner.read_area_file(kind, content)

    async def mission_file(
        self, survey_id: str, vehicle_id: str, kind: MissionFormat
    ) -> str | Mapping[str, Any]:
        """One drone's survey mission as a file other tools open: a QGroundControl `.plan`,
        a `QGC WPL 110` waypoint file, or its path as GeoJSON."""
        run = await self.find(survey_id)
        drone = run.drone(vehicle_id)
        if drone is None:
            raise InvalidRequest("vehicle_id", f"vehicle {vehicle_id} is not in survey {survey_id}")
        if kind == "geojson":
            return mission_path_geojson(drone.items)
        record = {r.id: r for r in self._hub.registry.all()}.get(vehicle_id)
        state = record.state if record is not None else None
        if (
            state is None
            or state.home_lat is None
            or state.home_lon is None
            or state.home_alt_msl is None
        ):
            # Never 0, 0, 0: a tool that takes the file's home would put it at 0°N 0°E.
            raise Conflict(
                f"{vehicle_id} has not reported its home yet, which a .plan or .waypoints file "
                "carries; the GeoJSON path does not need it"
            )
        home_point = (state.home_lat, state.home_lon, state.home_alt_msl)
        if kind == "wpl":
            return to_wpl(drone.items, home_point)
        return to_qgc_plan(drone.items, home_point)

    def _chosen(self, vehicle_ids: Sequence[str]) -> dict[str, VehicleRecord]:
        if len(set(vehicle_ids)) != len(vehicle_ids):
            raise InvalidRequest("vehicle_ids", "each vehicle may be chosen once")
        known = {record.id: record for record in self._hub.registry.all()}
        if unknown := [vid for vid in vehicle_ids if vid not in known]:
            raise InvalidRequest("vehicle_ids", f"unknown vehicles: {', '.join(unknown[:10])}")
        return {vid: known[vid] for vid in vehicle_ids}


def _fleet(records: Mapping[str, VehicleRecord]) -> list[Fleet]:
    """Where each chosen drone is and its home: the planner needs both."""
    fleet = []
    for vid, record in records.items():
        snapshot = snapshot_of(record)
        here, base = position(snapshot), home(snapshot)
        if here is None or base is None:
            raise InvalidRequest(
                "vehicle_ids", f"vehicle {vid} has no position or home yet; wait for its GPS"
            )
        fleet.append(Fleet(vid, here, base))
    return fleet
