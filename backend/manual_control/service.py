"""The manual-control lease's life on the hub: granted only once the agent has opened
browser control, ended (and said to every dashboard, and audited) however it ends.

How a lease ends, and who tells the vehicle:
- released by its holder, revoked by an admin, expired without input: the hub sends
  ``manual_stop`` and the agent holds the vehicle;
- ended on the vehicle (the deadman, frozen input, the hold button, a mode change the
  agent did not make, such as the RC transmitter's switch): the agent has held or
  yielded already and says so in a "manual" event (backend/realtime/agent_gateway/inbound.py);
- the hub restarted: leases live only in memory, so none survives; at start the hub
  finds in the audit log the ones that were open and reports them revoked.

``ManualControl`` is the service: the hub holds one (``Hub.manual_control``), and the live
sessions reach it through it (``backend/realtime/client_feed.py`` for the pilot's lease
and sticks, ``agent_gateway/inbound.py`` for the agent's word).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from collections.abc import Awaitable, Callable, Collection
from typing import Protocol, runtime_checkable

from sqlalchemy import Engine, select
from sqlalchemy.exc import SQLAlchemyError
from sqlalchemy.orm import Session
from starlette.websockets import WebSocketDisconnect

from backend.audit import AuditAction, AuditEntry
from backend.auth.policy import Principal
from backend.errors import GcsError
from backend.fleet.commands import CommandDispatcher, Sender
from backend.fleet.registry import FleetRegistry
from backend.manual_control.lease import Lease, LeaseBook, LeaseRefused
from backend.storage.models import AuditRow
from protocol.messages import (
    LeaseState,
    ManualEcho,
    ManualStartCommand,
    ManualStopCommand,
    Message,
)
from protocol.mission_rules import MISSION_MODES

log = logging.getLogger(__name__)

EXPIRY_CHECK_S = 0.1  # how often the hub looks for leases that input stopped renewing
RESTART_SCAN_ROWS = 10_000  # the newest lease audit rows read at start
# An agent's "manual" event this severe (WARNING) or worse: browser control has ended on
# the vehicle (its deadman, the autopilot taking over, a refusal).
MANUAL_ENDED_SEVERITY = 4


def ends_manual_control(kind: str, severity: int | None) -> bool:
    """Whether an agent's event says browser control has ended on its vehicle (the agent
    gateway and the fleet link both ask; an event without a severity counts as DEBUG).
    EMERGENCY is severity 0: a missing severity is tested with ``is None``, since
    ``severity or 7`` read the most severe event as the least."""
    level = 7 if severity is None else severity
    return kind == "manual" and level <= MANUAL_ENDED_SEVERITY


class Feed(Protocol):
    """A client's live feed, as the hub keeps it."""

    user: str


@runtime_checkable
class LeaseListener(Protocol):
    """A client connection that is told who flies each vehicle by hand (the live feed;
    the 3D view's relay is not)."""

    async def send(self, message: Message) -> None: ...


def lease_state(lease: Lease, reason: str = "") -> LeaseState:
    return LeaseState(
        vehicle_id=lease.vehicle_id,
        holder=lease.holder,
        reason=reason,
        resume_mode=lease.resume_mode,
    )


class ManualControl:
    def __init__(
        self,
        registry: FleetRegistry,
        dispatcher: CommandDispatcher,
        feeds: Collection[Feed],
        record: Callable[[AuditEntry], Awaitable[None]],
        leases: LeaseBook | None = None,
    ) -> None:
        """``feeds``: the hub's live client feeds (the collection itself, as they come
        and go); ``record``: writes an audit entry."""
        # In memory only, so a restart leaves every lease revoked.
        self.leases = leases or LeaseBook()
        self._registry = registry
        self._dispatcher = dispatcher
        self._feeds = feeds
        self._record = record

    async def announce(self, state: LeaseState) -> None:
        """Tell every dashboard who flies the vehicle by hand now."""
        self.leases.last_states[state.vehicle_id] = state
        for feed in list(self._feeds):
            if isinstance(feed, LeaseListener):
                with contextlib.suppress(RuntimeError, OSError, WebSocketDisconnect):
                    await feed.send(state)

    async def echo(self, vehicle_id: str, seq: int, sent_ms: float | None) -> None:
        """The agent flew the holder's frame ``seq``: tell the holder's feeds (the pilot
        view's input-to-vehicle delay), nobody else."""
        lease = self.leases.holder(vehicle_id)
        if lease is None:
            return
        message = ManualEcho(vehicle_id=vehicle_id, seq=seq, sent_ms=sent_ms)
        for feed in list(self._feeds):
            if feed.user == lease.holder and isinstance(feed, LeaseListener):
                with contextlib.suppress(RuntimeError, OSError, WebSocketDisconnect):
                    await feed.send(message)

    async def acquire(self, vehicle_id: str, principal: Principal) -> Lease:
        """Reserve the lease, have the agent open browser control, then grant it."""
        leases = self.leases
        renewing = leases.holder(vehicle_id)
        lease = leases.acquire(vehicle_id, principal)
        if renewing is not None:
            return lease  # the holder asking again: already open on the vehicle
        if leases.claims is not None:
            try:
                await leases.claims.claim(vehicle_id, principal.name)
            except LeaseRefused:
                leases.cancel(lease)
                raise
        record = self._registry.get(vehicle_id)
        mode = record.state.mode if record.state is not None else None
        try:
            outcome = await self._dispatcher.execute(
                vehicle_id, ManualStartCommand(), Sender(principal, "ws")
            )
        except GcsError as error:
            await self._cancel(lease)
            raise LeaseRefused(f"{vehicle_id}: {error.message}") from None
        if outcome.status != "accepted":
            await self._cancel(lease)
            raise LeaseRefused(f"{vehicle_id}: {outcome.message}", outcome.fix)
        if outcome.values and outcome.values.get("mission_paused") and mode in MISSION_MODES:
            lease.resume_mode = mode
        leases.started(lease)
        return lease

    async def _cancel(self, lease: Lease) -> None:
        self.leases.cancel(lease)
        if self.leases.claims is not None:
            await self.leases.claims.release(lease.vehicle_id, lease.holder)

    async def end(self, lease: Lease, reason: str, *, stop_vehicle: bool) -> None:
        """A lease is over: the vehicle holds (if the hub ended it), everyone is told."""
        if self.leases.claims is not None:
            await self.leases.claims.release(lease.vehicle_id, lease.holder)
        if stop_vehicle:
            try:
                sender = None if lease.principal is None else Sender(lease.principal, "ws")
                outcome = await self._dispatcher.execute(
                    lease.vehicle_id, ManualStopCommand(), sender
                )
                if outcome.status != "accepted":
                    log.warning("%s: hold after the lease refused: %s", lease.vehicle_id, outcome)
            except GcsError as error:
                # Offline or silent: its deadman has held it already.
                log.info("%s: no manual_stop sent: %s", lease.vehicle_id, error.message)
        ended = LeaseState(
            vehicle_id=lease.vehicle_id, holder=None, reason=reason, resume_mode=lease.resume_mode
        )
        await self.announce(ended)

    async def end_on_vehicle(self, vehicle_id: str, why: str) -> None:
        """The agent ended browser control itself: the lease goes with it, so the stream
        cannot quietly take the vehicle back."""
        lease = self.leases.revoke(vehicle_id)
        if lease is None:
            return
        log.info("manual-control lease of %s ended: %s", vehicle_id, why)
        await self._record(_hub_entry(vehicle_id, "end", why, lease.holder))
        await self.end(lease, why, stop_vehicle=False)

    async def watch_expiry(self) -> None:
        """Leases that input stopped renewing end, and everyone is told."""
        leases = self.leases
        while True:
            for lease in leases.expired():
                reason = f"expired: no input from {lease.holder} for {leases.limits.expiry_s:g} s"
                await self._record(_hub_entry(lease.vehicle_id, "end", reason, lease.holder))
                await self.end(lease, reason, stop_vehicle=True)
            if leases.claims is not None:
                await leases.claims.renew_due(leases.current())
            # Polling: an expiry is the absence of an event.
            await asyncio.sleep(EXPIRY_CHECK_S)

    async def revoke_left_open(self, audit_engine: Engine) -> list[str]:
        """At start: the leases open when the hub stopped are revoked, audited and
        reported to every dashboard that connects, never silently active."""
        try:
            rows = await asyncio.to_thread(_lease_rows, audit_engine)
        except SQLAlchemyError as error:
            log.error("could not read the lease audit at start: %s", error)
            return []
        revoked = []
        for vehicle_id, holder in leases_left_open(rows).items():
            reason = f"revoked: the hub restarted while {holder} held it"
            await self._record(_hub_entry(vehicle_id, "revoke", reason, holder))
            self.leases.last_states[vehicle_id] = LeaseState(
                vehicle_id=vehicle_id, holder=None, reason=reason
            )
            revoked.append(vehicle_id)
            log.warning("manual-control lease of %s %s", vehicle_id, reason)
        return revoked


def _hub_entry(vehicle_id: str, action: str, reason: str, holder: str) -> AuditEntry:
    return AuditEntry(
        actor="hub",
        role="system",
        source="hub",
        action=AuditAction.CONTROL_LEASE,
        target=vehicle_id,
        outcome="ok",
        detail={"action": action, "reason": reason, "holder": holder},
    )


def leases_left_open(rows: list[AuditRow]) -> dict[str, str]:
    """Vehicle -> holder of the leases the audit log shows granted and never ended
    (``rows`` newest first)."""
    last: dict[str, dict[str, str]] = {}
    for row in rows:
        if row.outcome != "ok" or row.target in last:
            continue
        try:
            detail = json.loads(row.detail)
        except ValueError:
            continue
        last[row.target] = {"action": detail.get("action", ""), "holder": row.actor}
    return {v: d["holder"] for v, d in last.items() if d["action"] == "acquire"}


def _lease_rows(audit_engine: Engine) -> list[AuditRow]:
    """The newest lease rows of the audit log, newest first."""
    statement = (
        select(AuditRow)
        .where(AuditRow.action == AuditAction.CONTROL_LEASE)
        .order_by(AuditRow.id.desc())
        .limit(RESTART_SCAN_ROWS)
    )
    with Session(audit_engine) as session:
        return list(session.scalars(statement).all())
