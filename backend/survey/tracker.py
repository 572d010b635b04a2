"""Following the surveys this hub drives from the vehicles' events and states on the bus:

- a "mission" event (MISSION_ITEM_REACHED) or MISSION_CURRENT past a lane's exit: flown;
- a "camera" event (CAMERA_FEEDBACK): a photo, with where it was taken;
- a drone that leaves its mission (RTL or LAND: a failsafe or a pilot), whose agent is gone
  for longer than GCS_SURVEY_LINK_TIMEOUT_S, whose battery falls below the floor, or that
  the operator takes out, drops out: its unflown lanes are split among the drones still
  flying and offered (flight/handover.py).

Each survey is stored whole (JSON) on every change, at most once per update interval, so a
restarted hub picks up where it was; progress goes out on the bus as SurveyUpdate. With
several hubs, only the one that holds a survey's claim (ownership.py) acts on it.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable

from sqlalchemy.exc import SQLAlchemyError

from backend.errors import GcsError, NotFound
from backend.fleet.collaborators import CommandServices
from backend.realtime.bus import Bus, LatestSubscription, ReliableSubscription, Topic
from backend.safety.snapshot import home, position, snapshot_of
from backend.settings import HubSettings
from backend.survey.flight.handover import flyer_of, handover_missions
from backend.survey.flight.progress import progress_of
from backend.survey.flight.run import (
    ACTIVE_STATES,
    LEAVING_MODES,
    DroneRun,
    DroneState,
    SurveyRun,
    SurveyState,
    geometry,
)
from backend.survey.ownership import SurveyOwnership
from backend.survey.repository import StoredSurvey, SurveyRepository
from protocol.messages import LiveEvent, Photo, SurveyUpdate, VehicleSummary

log = logging.getLogger(__name__)

EVENT_QUEUE = 10_000  # events waiting for the survey loop; a full queue makes agents wait


class SurveyTracker:
    """The surveys in memory and what follows them; the service (service.py) adds what
    the operators ask for."""

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

    async def load(self) -> None:
        """The surveys that were going on when the hub stopped."""
        states = [state.value for state in ACTIVE_STATES]
        for stored in await asyncio.to_thread(self._repository.in_states, states):
            if await self._drives(stored.id):
                await self._resume(stored)

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
            with contextlib.suppress(SQLAlchemyError):
                await self._save_dirty()

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
        return progress_of(run)

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

    def _busy_vehicles(self) -> dict[str, str]:
        return {
            d.vehicle_id: run.id
            for run in self._runs.values()
            if run.state in ACTIVE_STATES
            for d in run.drones
            if d.state in (DroneState.ASSIGNED, DroneState.FLYING)
        }
