"""A running formation's relay: the leader's state to every follower, with the other
members' positions for the separation check, and the leader's scans.

The followers' control runs in their agents (vehicle_agents/control/formation_runner.py),
close to the aircraft; the hub only moves data. Each tick sends every follower the newest
leader state (newest wins, nothing queues behind a slow link).

A virtual leader is the route's clock on the hub. A vehicle leader is itself a member:
its agent follows the virtual route at a zero offset, facing along it, and the followers
take the leader vehicle's reported state, so they keep station on where it really is.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass

from pydantic import ValidationError

from backend.fleet.registry import FleetRegistry
from backend.formation.active import ActiveFormation
from common.formation import LeaderState, slot_target
from common.geodesy import LocalFrame
from protocol.messages import LeaderScan, LeaderUpdate, Message, Neighbour

log = logging.getLogger(__name__)

# A leader sample older than this is not relayed: the followers' own 1 s rule then holds
# them, rather than a relayed state that looks fresh.
MAX_RELAY_AGE_S = 1.0
# The route's clock starts once every follower is this close to its slot (horizontally
# and vertically): a leg flown while followers are still joining measures nothing.
FORM_UP_M = 0.5
# The leader's scans go to the followers at most this often (the newest, never a queue):
# an obstacle moves with the scene, not the sensor's 10 Hz, and each scan is kilobytes.
SCAN_RELAY_HZ = 2.0


@dataclass(frozen=True)
class ScanPoints:
    """A vehicle's newest scan as a formation's followers get it: its time, its number,
    and its returns' north and east metres on the formation's plane."""

    time: float
    seq: int
    north: Sequence[float]
    east: Sequence[float]


# (vehicle id, the formation's frame, the scan number already relayed) -> its newest
# scan if newer (backend/formation/leader_scans.py reads the scan service's).
ScanSource = Callable[[str, LocalFrame, int | None], ScanPoints | None]
# Sends one message to one member's agent (a member offline is skipped).
Send = Callable[[str, Message], Awaitable[None]]


class FormationRelay:
    def __init__(
        self,
        registry: FleetRegistry,
        send: Send,
        scan_source: ScanSource | None = None,
        speedup: float = 1.0,
    ) -> None:
        self._registry = registry
        self._speedup = speedup  # the vehicles' seconds per wall second (FormationService)
        self._send = send
        self.scan_source = scan_source

    def local(self, formation: ActiveFormation, vehicle_id: str) -> Neighbour | None:
        """A member's last report in the formation's frame, with its velocity and time
        (a consensus follower predicts its neighbours forward over the delay)."""
        record = self._registry.get(vehicle_id)
        state = record.state
        if state is None or state.lat is None or state.lon is None or state.alt_rel is None:
            return None
        east, north = formation.plan.frame.to_local(state.lat, state.lon)
        return Neighbour(
            vehicle_id=vehicle_id,
            north=north,
            east=east,
            up=state.alt_rel,
            vn=_bounded(state.vn),
            ve=_bounded(state.ve),
            vu=_bounded(state.climb_rate),
            time=record.last_seen,
        )

    def leader_state(self, formation: ActiveFormation, now: float) -> LeaderState | None:
        """The route's state now (a virtual leader), or the leader vehicle's last report."""
        if formation.plan.leader_id is None:
            v = formation.plan.route.state_at(route_time(formation, now, self._speedup))
            return LeaderState(v.north, v.east, v.up, v.vn, v.ve, v.vu, v.heading_rad, now)
        record = self._registry.get(formation.plan.leader_id)
        state, seen = record.state, record.last_seen
        here = self.local(formation, formation.plan.leader_id)
        if state is None or seen is None or here is None:
            return None
        if (now - seen) * self._speedup > MAX_RELAY_AGE_S:  # in the vehicles' seconds
            return None
        heading = math.radians(state.heading_deg or 0.0)
        return LeaderState(
            here.north,
            here.east,
            here.up,
            state.vn or 0.0,
            state.ve or 0.0,
            state.climb_rate or 0.0,
            heading,
            seen,
        )

    def joining(self, formation: ActiveFormation, leader: LeaderState | None) -> list[str]:
        """Each follower not yet within FORM_UP_M of its slot around the leader, and why."""
        if leader is None:
            return [f"the leader {formation.plan.leader_id}'s state is not known"]
        out = []
        for follower, offset in formation.offsets.items():
            here = self.local(formation, follower)
            if here is None:
                out.append(f"{follower}'s position is not known")
                continue
            (north, east, up), _ = slot_target(leader, offset)
            distance = math.dist((north, east, up), (here.north, here.east, here.up))
            if distance > FORM_UP_M:
                out.append(f"{follower} is {distance:.1f} m from its slot")
        return out

    async def relay(self, formation: ActiveFormation, now: float) -> None:
        """One tick: the route to a leader vehicle, the leader's state to the followers
        (the route's clock started once they are all in their slots), their tracking
        measured, and the leader's newest scan."""
        route = formation.plan.route.state_at(route_time(formation, now, self._speedup))
        if formation.plan.leader_id is not None:
            # the leader vehicle flies the route itself, at a zero offset
            await self._send(formation.plan.leader_id, _update(formation, route, now, []))
        leader = self.leader_state(formation, now)
        if leader is None:
            return
        if formation.formed_at is None and not self.joining(formation, leader):
            formation.formed_at = now
            log.info("%s formed up: the route starts", formation.id)
        self._measure(formation, leader, now)
        places = [p for v in formation.members if (p := self.local(formation, v))]
        for follower in formation.followers:
            others = [p for p in places if p.vehicle_id != follower]
            await self._send(follower, _update(formation, leader, leader.time_s, others))
        await self._relay_scan(formation, now)

    def _measure(self, formation: ActiveFormation, leader: LeaderState, now: float) -> None:
        """Each follower's error from its slot at the time of its own report, the
        leader carried there at its velocity (at most a second either way)."""
        leg = None
        if formation.formed_at is not None:
            index = formation.plan.route.leg_at(route_time(formation, now, self._speedup))
            leg = None if index is None else index + 1
        for follower, offset in formation.offsets.items():
            seen = self._registry.get(follower).last_seen
            here = self.local(formation, follower)
            if seen is None or here is None:
                continue
            dt = max(-1.0, min(1.0, (seen - leader.time_s) * self._speedup))
            then = LeaderState(
                leader.north + leader.vn * dt,
                leader.east + leader.ve * dt,
                leader.up + leader.vu * dt,
                leader.vn,
                leader.ve,
                leader.vu,
                leader.heading_rad,
                seen,
            )
            (north, east, up), _ = slot_target(then, offset)
            error = (here.north - north, here.east - east, here.up - up)
            formation.metrics.record(follower, seen, error, leg)

    async def _relay_scan(self, formation: ActiveFormation, now: float) -> None:
        """The leader vehicle's newest scan to every follower, at most SCAN_RELAY_HZ."""
        leader_id = formation.plan.leader_id
        if leader_id is None or self.scan_source is None:
            return
        if now - formation.scan_relayed_at < 1.0 / SCAN_RELAY_HZ:
            return
        scan = self.scan_source(leader_id, formation.plan.frame, formation.scan_seq)
        if scan is None:
            return
        formation.scan_seq, formation.scan_relayed_at = scan.seq, now
        try:
            message = LeaderScan(
                formation_id=formation.id,
                time=scan.time,
                seq=scan.seq,
                north=list(scan.north),
                east=list(scan.east),
            )
        except ValidationError as error:
            # points beyond the protocol's reach of the formation's origin: not relayed,
            # and the relay of the leader's state goes on
            log.warning("%s: scan %d not relayed: %s", formation.id, scan.seq, error)
            return
        for follower in formation.followers:
            await self._send(follower, message)


def route_time(formation: ActiveFormation, now: float, speedup: float = 1.0) -> float:
    """Seconds along the leader's route (the vehicles' seconds): none until every follower
    is in its slot."""
    if formation.formed_at is None:
        return 0.0
    return (now - formation.formed_at) * speedup


def _update(
    formation: ActiveFormation, leader: LeaderState, time_s: float, others: list[Neighbour]
) -> LeaderUpdate:
    return LeaderUpdate(
        formation_id=formation.id,
        time=time_s,
        north=leader.north,
        east=leader.east,
        up=leader.up,
        vn=leader.vn,
        ve=leader.ve,
        vu=leader.vu,
        heading_deg=math.degrees(leader.heading_rad) % 360.0,
        neighbours=others,
    )


def _bounded(speed: float | None) -> float:
    """A reported speed within the protocol's bounds (a glitching sensor's value must
    not stop the relay)."""
    if speed is None or not math.isfinite(speed):
        return 0.0
    return max(-99.0, min(99.0, speed))
