"""Area surveys in flight: create (plan, split, check), start, follow, hand over, abort.

The planning is pure (backend.survey.planning); this service is the part that talks to the
fleet: it checks each drone is free and ready, has every part's mission checked by the
safety rails before anything is uploaded, uploads and starts the missions together through
the same command path as the operators' own commands (audited, rails-checked), and follows
each drone from the vehicles' events and states on the bus:

- a "mission" event (MISSION_ITEM_REACHED) or MISSION_CURRENT past a lane's exit: flown;
- a "camera" event (CAMERA_FEEDBACK): a photo, with where it was taken;
- a drone that leaves its mission (RTL or LAND: a failsafe or a pilot), whose agent is gone
  for longer than GCS_SURVEY_LINK_TIMEOUT_S, whose battery falls below the floor, or that
  the operator takes out, drops out: its unflown lanes are split among the drones still
  flying and offered; the operator's one "accept" uploads the new missions, each resuming
  from where the drone is.

Each survey is stored whole (JSON) on every change, at most once per update interval, so a
restarted hub picks up where it was; progress goes out on the bus as SurveyUpdate.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
import uuid
from collections.abc import Callable, Sequence
from dataclasses import asdict

from sqlalchemy.exc import SQLAlchemyError

from backend.auth.policy import Principal
from backend.auth.rate_limit import Limit, RateLimiter
from backend.errors import Conflict, GcsError, InvalidRequest, NotFound, SafetyViolation
from backend.fleet.collaborators import CommandServices
from backend.fleet.command_service import execute_command
from backend.fleet.registry import VehicleRecord
from backend.fleet.safety_gate import snapshot_of
from backend.realtime.bus import Bus, LatestSubscription, ReliableSubscription, Topic
from backend.safety.snapshot import home, position
from backend.settings import HubSettings
from backend.survey.flight.handover import accept_offer, flyer_of, handover_missions
from backend.survey.flight.run import (
    ACTIVE_STATES,
    LEAVING_MODES,
    DroneRun,
    DroneState,
    LaneRecord,
    SurveyRun,
    SurveyState,
    covered_fraction,
    geometry,
)
from backend.survey.ownership import SurveyOwnership
from backend.survey.plan_workers import ClientWatch, SurveyPlanner
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet, SurveyPlan
from backend.survey.repository import StoredSurvey, SurveyRepository
from protocol.messages import (
    ArmCommand,
    Command,
    DisarmCommand,
    LiveEvent,
    MissionSetCurrentCommand,
    MissionUploadCommand,
    Photo,
    ReturnToLaunchCommand,
    SetModeCommand,
    SurveyDroneProgress,
    SurveyUpdate,
    TakeoffCommand,
    VehicleSummary,
)
from protocol.mission_rules import mission_mode

log = logging.getLogger(__name__)

SOURCE = "survey"  # the audit log's source for the commands a survey sends
EVENT_QUEUE = 10_000  # events waiting for the survey loop; a full queue makes agents wait


class SurveyService:
    def __init__(
        self,
        hub: CommandServices,
        bus: Bus,
        repository: SurveyRepository,
        settings: HubSettings,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._hub = hub
        self._bus = bus
        self._repository = repository
        self._settings = settings
        self._clock = clock
        self._runs: dict[str, SurveyRun] = {}
        self._owners: dict[str, str] = {}
        self._dirty: set[str] = set()
        self._gone_since: dict[str, float] = {}
        self._landed_since: dict[tuple[str, str], float] = {}
        self._lock = asyncio.Lock()  # one change to the surveys at a time
        # Several hubs: the claims that make one hub drive each survey (None: this hub
        # is alone and drives them all).
        self.ownership: SurveyOwnership | None = None
        # Plans off the event loop, bounded (plan_workers.py); the preview plans here too.
        self.planner = SurveyPlanner(settings)
        # Area files (KML, GeoJSON, .plan) each user may import (routes.py), parsed
        # in the planner's import worker.
        self.import_limiter = RateLimiter(Limit(settings.survey_imports_per_minute, 60.0))

    # -- life cycle ----------------------------------------------------------------------

    async def load(self) -> None:
        """The surveys that were going on when the hub stopped."""
        states = [state.value for state in ACTIVE_STATES]
        for stored in await asyncio.to_thread(self._repository.in_states, states):
            if await self._drives(stored.id):
                await self._resume(stored)

    async def _drives(self, survey_id: str) -> bool:
        """Whether this hub drives the survey (claimed or renewed just now)."""
        if self.ownership is None:
            return True
        other = await self.ownership.take(survey_id)
        if other is not None:
            log.info("survey %s is driven by hub %s", survey_id, other)
        return other is None

    async def _resume(self, stored: StoredSurvey) -> None:
        try:
            run = SurveyRun.model_validate_json(stored.run_json)
        except ValueError as error:
            log.error("stored survey %s unreadable, left as it is: %s", stored.id, error)
            return
        self._runs[run.id] = run
        self._owners[run.id] = stored.created_by
        if run.started is not None:
            # Photos the flight log stored after this survey's last save (the hub
            # acknowledged them, so the agents will not send them again).
            vehicles = [d.vehicle_id for d in run.drones]
            found = await asyncio.to_thread(self._repository.photos, vehicles, run.started)
            added = sum(
                run.photo(
                    p.vehicle_id,
                    Photo(index=p.index, lat=p.lat, lon=p.lon, alt_rel=p.alt_rel),
                    p.time,
                )
                for p in found
            )
            log.info("survey %s resumed (%s), %d photos from the log", run.id, run.state, added)
        else:
            log.info("survey %s resumed (%s)", run.id, run.state)

    async def run(self) -> None:
        events = ReliableSubscription(EVENT_QUEUE)
        states = LatestSubscription()
        self._bus.subscribe(Topic.VEHICLE_EVENT, events)
        self._bus.subscribe(Topic.VEHICLE_STATE, states)
        try:
            async with asyncio.TaskGroup() as tasks:
                tasks.create_task(self._follow_events(events))
                tasks.create_task(self._follow_states(states))
                tasks.create_task(self._tick())
        finally:
            self._bus.unsubscribe(Topic.VEHICLE_EVENT, events)
            self._bus.unsubscribe(Topic.VEHICLE_STATE, states)
            self.planner.close()
            with contextlib.suppress(SQLAlchemyError):
                await self._save_dirty()

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
        fleet = []
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
            snapshot = snapshot_of(record)
            here, base = position(snapshot), home(snapshot)
            if here is None or base is None:
                raise InvalidRequest(
                    "vehicle_ids", f"vehicle {vid} has no position or home yet; wait for its GPS"
                )
            fleet.append(Fleet(vid, here, base))
        survey = await self.planner.plan(request, fleet, gone)
        violations: list[dict[str, object]] = []
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
        """Upload every drone's mission, then start them all together (`_launch`). An
        upload refused anywhere starts nothing."""
        run = self.get(survey_id)
        if run.state is not SurveyState.PLANNED:
            raise Conflict(f"survey {survey_id} is {run.state}; only a planned one can start")
        uploads = await asyncio.gather(
            *(
                self._send(principal, d.vehicle_id, MissionUploadCommand(items=d.items))
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
        started = await asyncio.gather(*(self._launch(principal, run, d) for d in run.drones))
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
                self._send(principal, vid, MissionUploadCommand(items=items))
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
            *(self._send(principal, vid, MissionSetCurrentCommand(seq=1)) for vid in offer.missions)
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
        await asyncio.gather(*(self._send(principal, v, ReturnToLaunchCommand()) for v in flying))
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
        await self._send(principal, vehicle_id, ReturnToLaunchCommand())
        async with self._lock:
            self._drop(run, drone, f"taken out by {principal.name}")
            await self._save(run)
        return run

    # -- reading -------------------------------------------------------------------------

    def active(self) -> list[SurveyRun]:
        return [run for run in self._runs.values() if run.state in ACTIVE_STATES]

    def known(self) -> list[SurveyRun]:
        """Every survey this hub has followed since it started, ended ones too: photos
        reach the hub late after an outage."""
        return list(self._runs.values())

    def get(self, survey_id: str) -> SurveyRun:
        run = self._runs.get(survey_id)
        if run is None:
            raise NotFound(f"no survey {survey_id}")
        return run

    async def find(self, survey_id: str) -> SurveyRun:
        """A survey in memory, or one the store holds (ended before this hub started)."""
        if survey_id in self._runs:
            return self._runs[survey_id]
        stored = await asyncio.to_thread(self._repository.get, survey_id)
        if stored is None:
            raise NotFound(f"no survey {survey_id}")
        return SurveyRun.model_validate_json(stored.run_json)

    def update_of(self, run: SurveyRun) -> SurveyUpdate:
        covered = covered_fraction(run, geometry(run))
        return SurveyUpdate(
            survey_id=run.id,
            state=run.state.value,
            lanes_done=run.lanes_done(),
            lanes_total=run.lanes_total(),
            photos=run.photo_count(),
            covered_pct=min(100.0, round(covered * 100, 3)),
            drones=[
                SurveyDroneProgress(
                    vehicle_id=d.vehicle_id,
                    state=d.state.value,
                    lanes_done=d.lanes_done_before + sum(lane.done for lane in d.lanes),
                    lanes_total=d.lanes_done_before + len(d.lanes),
                    photos=len(d.photos),
                    reason=d.reason,
                )
                for d in run.drones
            ],
            handover_lanes=run.offer.lanes_moved if run.offer else None,
        )

    # -- following the fleet -------------------------------------------------------------

    def _flying_runs(
        self, vehicle_id: str, states: frozenset[DroneState] = frozenset({DroneState.FLYING})
    ) -> list[tuple[SurveyRun, DroneRun]]:
        out = []
        for run in self._runs.values():
            if run.state in (SurveyState.FLYING, SurveyState.HANDOVER_OFFERED):
                drone = run.drone(vehicle_id)
                if drone is not None and drone.state in states:
                    out.append((run, drone))
        return out

    async def _follow_events(self, events: ReliableSubscription) -> None:
        while True:
            event = await events.get()
            if not isinstance(event, LiveEvent) or event.kind not in ("mission", "camera"):
                continue
            async with self._lock:
                if event.kind == "camera" and event.photo is not None:
                    # Any survey the drone flew when it took the photo, even one it has
                    # finished or dropped out of: an agent back from an outage replays its
                    # photos, perhaps after the hub has seen it land.
                    for run in self._runs.values():
                        if run.photo(event.vehicle_id, event.photo, event.time):
                            self._dirty.add(run.id)
                elif event.kind == "mission" and event.mission_item is not None:
                    for run, _ in self._flying_runs(event.vehicle_id):
                        if run.reached(event.vehicle_id, event.mission_item):
                            self._dirty.add(run.id)

    async def _follow_states(self, states: LatestSubscription) -> None:
        while True:
            for summary in await states.drain():
                if isinstance(summary, VehicleSummary):
                    async with self._lock:
                        self._on_state(summary)

    def _on_state(self, summary: VehicleSummary) -> None:
        vid = summary.id
        if summary.connected:
            self._gone_since.pop(vid, None)
        else:
            self._gone_since.setdefault(vid, self._clock())
        state = summary.state
        for run, drone in self._flying_runs(vid):
            if state is None or not summary.connected:
                continue
            if run.current_item(vid, state.mission_current):
                self._dirty.add(run.id)
            drone.armed_seen = drone.armed_seen or state.armed
            if state.armed and state.landed_state in ("in_air", "takeoff", None):
                drone.airborne = drone.airborne or (state.alt_rel or 0) > 1.0
            remaining = drone.unflown()
            if (drone.airborne or drone.armed_seen) and not state.armed:
                # Landed: done if every lane is flown, else it stopped short. A drone that
                # landed while the hub was away has its "reached" events still coming (the
                # agent replays them): it is given the link timeout before it is judged.
                # One that disarmed without ever leaving the ground flew nothing, whatever
                # its mission's progress says (a jump to the last item marks every lane).
                key = (run.id, vid)
                landed = self._landed_since.setdefault(key, self._clock())
                if drone.airborne and not remaining:
                    drone.state = DroneState.DONE
                    drone.finished = time.time()
                elif self._clock() - landed >= self._settings.survey_link_timeout_s:
                    self._drop(
                        run,
                        drone,
                        "landed before its lanes were flown"
                        if drone.airborne
                        else "disarmed on the ground before it took off",
                    )
                else:
                    continue
                self._landed_since.pop(key, None)
                self._dirty.add(run.id)
            elif remaining and state.mode.upper() in LEAVING_MODES:
                self._drop(run, drone, f"left its mission: {state.mode}")
                self._dirty.add(run.id)
            elif (
                remaining
                and state.battery_remaining is not None
                and state.battery_remaining < self._settings.survey_battery_floor_pct
            ):
                self._drop(run, drone, f"battery low: {state.battery_remaining:.0f} %")
                self._dirty.add(run.id)
            self._settle(run)

    async def _tick(self) -> None:
        """Lost links by the clock; stores and announces what changed, paced."""
        interval = self._settings.survey_update_interval_s
        while True:
            async with self._lock:
                now = self._clock()
                for vid, since in list(self._gone_since.items()):
                    if now - since < self._settings.survey_link_timeout_s:
                        continue
                    for run, drone in self._flying_runs(vid):
                        self._drop(run, drone, f"link lost for {now - since:.0f} s")
                        self._settle(run)
                        self._dirty.add(run.id)
            try:
                await self._save_dirty()
            except SQLAlchemyError as error:
                # Kept in memory and marked dirty again: the next tick tries once more.
                log.warning("surveys not stored: %s", error)
            if self.ownership is not None:
                await self._keep_and_adopt(self.ownership)
            await asyncio.sleep(interval)  # pacing, not synchronisation

    async def _keep_and_adopt(self, ownership: SurveyOwnership) -> None:
        """Renew this hub's surveys, let go of any another hub took over, and take over
        those whose hub stopped renewing them."""
        for run in self.active():
            if not await self._drives(run.id):
                log.warning("survey %s: driven by another hub now; no longer here", run.id)
                async with self._lock:
                    self._runs.pop(run.id, None)
                    self._dirty.discard(run.id)
        if not ownership.time_to_adopt():
            return
        states = [state.value for state in ACTIVE_STATES]
        try:
            stored = await asyncio.to_thread(self._repository.in_states, states)
        except SQLAlchemyError as error:
            log.warning("surveys of other hubs not checked: %s", error)
            return
        for found in stored:
            if found.id not in self._runs and await self._drives(found.id):
                log.warning("survey %s: its hub stopped driving it; taken over here", found.id)
                async with self._lock:
                    await self._resume(found)

    def _drop(self, run: SurveyRun, drone: DroneRun, reason: str) -> None:
        log.warning("survey %s: %s drops out: %s", run.id, drone.vehicle_id, reason)
        drone.state = DroneState.DROPPED
        drone.reason = reason
        drone.finished = time.time()
        self._dirty.add(run.id)
        self._offer(run, reason=f"{drone.vehicle_id} {reason}")

    def _offer(self, run: SurveyRun, reason: str) -> None:
        """Split the lost lanes among the drones still flying, for the operator to accept."""
        if run.state not in (SurveyState.FLYING, SurveyState.HANDOVER_OFFERED):
            return
        if not run.orphans():
            self._settle(run)
            return
        flyers = []
        geo = geometry(run)
        for drone in run.drones:
            if drone.state is not DroneState.FLYING:
                continue
            try:
                record = self._hub.registry.get(drone.vehicle_id)
            except GcsError:
                continue
            snapshot = snapshot_of(record)
            here, base = position(snapshot), home(snapshot)
            if here is None or base is None or not record.connected:
                continue
            flyers.append(
                flyer_of(
                    drone,
                    geo,
                    geo.frame.to_local(here.lat, here.lon),
                    geo.frame.to_local(base.lat, base.lon),
                )
            )
        if not flyers:
            run.offer = None
            run.note = f"{reason}; no drone is left to take its lanes"
            self._settle(run)
            return
        run.offer = handover_missions(run, geo, flyers, reason)
        run.state = SurveyState.HANDOVER_OFFERED

    def _settle(self, run: SurveyRun) -> None:
        """The survey ends when no drone flies it any more."""
        if run.state not in (SurveyState.FLYING, SurveyState.HANDOVER_OFFERED):
            return
        if any(d.state in (DroneState.FLYING, DroneState.ASSIGNED) for d in run.drones):
            return
        if run.offer is not None:
            return  # the offer's drones are flying, or they would not be in it
        run.state = SurveyState.DONE
        if run.orphans():
            run.note = run.note or f"{len(run.orphans())} lanes were left unflown"
        self._dirty.add(run.id)

    # -- sending and storing -------------------------------------------------------------

    async def _send(self, principal: Principal, vehicle_id: str, command: Command) -> str | None:
        """None when the vehicle accepted, else why not."""
        try:
            outcome = await execute_command(self._hub, principal, SOURCE, vehicle_id, command)
        except GcsError as error:
            return error.message if hasattr(error, "message") else str(error)
        return None if outcome.status == "accepted" else outcome.message or outcome.status

    async def _launch(self, principal: Principal, run: SurveyRun, drone: DroneRun) -> str | None:
        """Start one drone on its uploaded mission, as QGroundControl's "Start Mission"
        does for its autopilot; None when it is off, else why not (and what was undone).

        Neither autopilot arms itself for a mission. ArduCopter flies AUTO from the ground
        only once "auto armed", which a GCS take-off gives it: a guided take-off (it
        arms), then AUTO. PX4 (PX4FirmwarePlugin::startMission): its mission mode, then
        arm; armed in Mission on the ground with a mission, it takes off on the take-off
        item. The mission mode's name is the one the vehicle's own mode list has."""
        record = self._hub.registry.get(drone.vehicle_id)
        mode = mission_mode(record.modes)
        if mode is None:
            return f"it has no mission mode (its modes: {', '.join(record.modes) or 'none'})"
        if mode != "AUTO":
            return await self._launch_in_mission_mode(principal, drone.vehicle_id, mode)
        why = await self._send(principal, drone.vehicle_id, TakeoffCommand(altitude=run.altitude_m))
        if why is not None:
            return f"take-off: {why}{await self._disarm_on_ground(principal, drone.vehicle_id)}"
        why = await self._send(principal, drone.vehicle_id, SetModeCommand(mode=mode))
        if why is None:
            return None
        # It took off but will not fly the mission: it must not be left hovering.
        back = await self._send(principal, drone.vehicle_id, ReturnToLaunchCommand())
        why += "; sent home" if back is None else f"; RTL also refused: {back}"
        return f"{mode}: {why}"

    async def _launch_in_mission_mode(
        self, principal: Principal, vehicle_id: str, mode: str
    ) -> str | None:
        """PX4: the mission mode, then arm. A refused mode change leaves the drone as it
        was; a refused (or unanswered) arming leaves it on the ground, made sure disarmed."""
        why = await self._send(principal, vehicle_id, SetModeCommand(mode=mode))
        if why is not None:
            return f"{mode}: {why}"
        why = await self._send(principal, vehicle_id, ArmCommand())
        if why is not None:
            return f"arm: {why}{await self._disarm_on_ground(principal, vehicle_id)}"
        return None

    async def _disarm_on_ground(self, principal: Principal, vehicle_id: str) -> str:
        """After a launch step failed once it may have armed: a plain disarm, which both
        autopilots take only on the ground (a flying drone keeps flying), so that nothing
        is left armed on the ground waiting for a mission that will not start. Returns
        what to add to the reason when it did not go through."""
        why = await self._send(principal, vehicle_id, DisarmCommand())
        return "" if why is None else f"; disarm also refused: {why}"

    async def _save(self, run: SurveyRun) -> None:
        stored = StoredSurvey(
            run.id,
            run.created,
            run.state.value,
            self._owners.get(run.id, ""),
            run.model_dump_json(),
        )
        await asyncio.to_thread(self._repository.save, stored)
        await self._bus.publish(Topic.SURVEYS, run.id, self.update_of(run))

    async def _save_dirty(self) -> None:
        while self._dirty:
            survey_id = self._dirty.pop()
            run = self._runs.get(survey_id)
            if run is None:
                continue
            try:
                await self._save(run)
            except SQLAlchemyError:
                self._dirty.add(survey_id)
                raise

    def _chosen(self, vehicle_ids: Sequence[str]) -> dict[str, VehicleRecord]:
        if len(set(vehicle_ids)) != len(vehicle_ids):
            raise InvalidRequest("vehicle_ids", "each vehicle may be chosen once")
        known = {record.id: record for record in self._hub.registry.all()}
        if unknown := [vid for vid in vehicle_ids if vid not in known]:
            raise InvalidRequest("vehicle_ids", f"unknown vehicles: {', '.join(unknown[:10])}")
        return {vid: known[vid] for vid in vehicle_ids}

    def _busy_vehicles(self) -> dict[str, str]:
        return {
            d.vehicle_id: run.id
            for run in self._runs.values()
            if run.state in ACTIVE_STATES
            for d in run.drones
            if d.state in (DroneState.ASSIGNED, DroneState.FLYING)
        }


def new_run(request: SurveyRequest, survey: SurveyPlan) -> SurveyRun:
    calc = survey.calc
    drones = []
    for part in survey.parts:
        lanes = [
            LaneRecord(start=(start[0], start[1]), end=(end[0], end[1]), entry=entry, exit=exit_)
            for (start, end), (entry, exit_) in zip(part.lane_paths, part.lane_items, strict=True)
        ]
        drones.append(DroneRun(vehicle_id=part.vehicle_id, items=part.items, lanes=lanes))
    return SurveyRun(
        id=uuid.uuid4().hex[:12],
        created=time.time(),
        request=request,
        altitude_m=calc.altitude_m,
        footprint_side_m=calc.footprint_side_m,
        footprint_frontal_m=calc.footprint_frontal_m,
        lane_spacing_m=calc.lane_spacing_m,
        trigger_distance_m=calc.trigger_distance_m,
        angle_deg=survey.angle_deg,
        drones=drones,
    )
