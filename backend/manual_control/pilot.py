"""A pilot's side of manual control on one live feed: the lease asked for, given back or
revoked (``control``), and the sticks (``input``), admitted by the lease and relayed
newest first. The feed (backend/realtime/client_feed.py) hands these messages here.

A refusal is told to the pilot at once (the pilot view shows it, and offers its fix to
whoever may make it), and to every dashboard in its event feed, once a window per
connection: a lease that silently never comes looks like a hub that hangs.
"""

from __future__ import annotations

import time
from collections.abc import Awaitable, Callable
from typing import Protocol

from backend.audit import AuditAction, AuditEntry, principal_audit_entry
from backend.auth.policy import Principal
from backend.errors import Forbidden, VehicleNotFound
from backend.fleet.registry import FleetRegistry
from backend.manual_control.lease import Lease, LeaseRefused
from backend.manual_control.relay import ManualRelay
from backend.manual_control.service import ManualControl, lease_state
from backend.observability.metrics import count_rejected
from protocol.messages import (
    ControlRequest,
    ErrorReply,
    HubEventKind,
    LeaseRefusal,
    ManualFrame,
    ManualInput,
    Message,
    ParamFix,
)

REFUSAL_SEVERITY = 4  # MAV_SEVERITY_WARNING: a lease refused, in every event feed
# A pilot clicking "Take control" again gets the refusal again, but the flight log and the
# other dashboards have it: the same refusal from one connection is stored once a window.
REFUSAL_EVENT_WINDOW_S = 60.0
MAX_REFUSALS_REMEMBERED = 64
CONTROL_VERBS = {"acquire": "take", "release": "give back", "revoke": "revoke"}


class PilotServices(Protocol):
    """What a pilot's channel uses of the hub."""

    @property
    def registry(self) -> FleetRegistry: ...

    @property
    def manual_control(self) -> ManualControl: ...

    async def record(self, entry: AuditEntry) -> None: ...

    async def store_event(
        self, vehicle_id: str, kind: HubEventKind, text: str, severity: int | None = None
    ) -> None: ...


class PilotChannel:
    def __init__(
        self, hub: PilotServices, send: Callable[[Message], Awaitable[None]], peer: str
    ) -> None:
        """``send``: to this feed's client; ``peer``: its address, for the audit log."""
        self._hub = hub
        self._send = send
        self._peer = peer
        # The sticks to the vehicles' agents, newest wins: run by the feed, with its tasks.
        self.relay = ManualRelay(
            hub.registry,
            hub.manual_control.leases.limits.max_rate_hz,
            on_collapse=self._count_collapse,
        )
        # (vehicle, action, reason) -> when this connection last stored that refusal
        self._refusals_stored: dict[tuple[str, str, str], float] = {}

    async def input(self, message: ManualInput, user: str) -> None:
        """Forward the lease holder's input, newest first; refuse and count the rest."""
        try:
            self._hub.manual_control.leases.admit(message.vehicle_id, user, message.seq)
        except LeaseRefused as refusal:
            count_rejected("client_manual")
            # Never forwarded. Old or too-fast frames are a client's jitter: counted
            # silently; input without the lease is said, since the pilot must know.
            if "lease" in refusal.message:
                await self._send(ErrorReply(code="forbidden", message=refusal.message))
            return
        self.relay.put(
            message.vehicle_id,
            # Its fields were validated as the ManualInput arrived: the hot path (25 Hz
            # per pilot) builds the relayed frame without validating them again.
            ManualFrame.model_construct(
                type="manual",
                seq=message.seq,
                axes=message.axes,
                source=message.source,
                sent_ms=message.sent_ms,
            ),
        )

    async def _refused(
        self,
        message: ControlRequest,
        user: str,
        reason: str,
        fix: ParamFix | None,
        *,
        known: bool,
    ) -> None:
        """Tell the pilot at once, and every dashboard once a window (an unknown
        vehicle gets no event row of its own)."""
        vehicle_id = message.vehicle_id
        # Said beside the vehicle's name, about manual control: those need no repeating.
        text = reason.removeprefix(f"{vehicle_id}: ").removeprefix("manual control: ")
        await self._send(
            LeaseRefusal(vehicle_id=vehicle_id, action=message.action, reason=text, fix=fix)
        )
        if known and self._first_in_window((vehicle_id, message.action, text)):
            await self._hub.store_event(
                vehicle_id,
                "manual",
                f"{user} may not {CONTROL_VERBS[message.action]} manual control: {text}",
                REFUSAL_SEVERITY,
            )

    def _first_in_window(self, key: tuple[str, str, str]) -> bool:
        """Whether this refusal is the first of its window on this connection."""
        now = time.monotonic()
        last = self._refusals_stored.get(key)
        if last is not None and now - last < REFUSAL_EVENT_WINDOW_S:
            return False
        if len(self._refusals_stored) >= MAX_REFUSALS_REMEMBERED:
            self._refusals_stored.clear()  # a bound, not a policy: forgetting says again
        self._refusals_stored[key] = now
        return True

    def _count_collapse(self) -> None:
        self._hub.manual_control.leases.refused.too_fast += 1

    async def control(self, message: ControlRequest, principal: Principal) -> None:
        """The lease asked for, given back or revoked: audited, and told to everyone."""
        vehicle_id = message.vehicle_id
        manual = self._hub.manual_control
        leases = manual.leases
        outcome, reason = "ok", ""
        ended: Lease | None = None
        try:
            if self._hub.registry.get(vehicle_id).channel is None:
                raise LeaseRefused(f"{vehicle_id} is offline")
            if message.action == "acquire":
                lease = await manual.acquire(vehicle_id, principal)
            elif message.action == "release":
                ended = leases.release(vehicle_id, principal)
                reason = f"released by {principal.name}"
            else:
                ended = leases.revoke(vehicle_id, principal)
                reason = f"revoked by {principal.name}"
        except (Forbidden, VehicleNotFound) as refusal:
            outcome = "refused"
            reason = refusal.message
            fix = refusal.fix if isinstance(refusal, LeaseRefused) else None
            await self._refused(
                message, principal.name, reason, fix, known=not isinstance(refusal, VehicleNotFound)
            )
        await self._hub.record(
            principal_audit_entry(
                principal,
                self._peer,
                AuditAction.CONTROL_LEASE,
                vehicle_id,
                outcome,
                {"action": message.action, "reason": reason},
            )
        )
        if outcome != "ok":
            return
        if message.action == "acquire":
            await manual.announce(lease_state(lease))
        elif ended is not None:
            await manual.end(ended, reason, stop_vehicle=True)
