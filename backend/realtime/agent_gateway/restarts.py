"""What an agent that restarted left unrecorded, said in the vehicle's flight log."""

from __future__ import annotations

import logging

from backend.errors import VehicleNotFound
from backend.fleet.registry import FleetRegistry
from protocol.messages import (
    Hello,
)

log = logging.getLogger(__name__)


def restart_gap(registry: FleetRegistry, hello: Hello, now: float) -> str | None:
    """What an agent that comes back as a new run (it restarted) left unrecorded: nothing
    was sampled between its earlier run's last sample the hub saw and this hello, and
    what that run had not yet had acknowledged, it kept only in memory. None when the
    same run reconnects (its outbox replays what is missing) or the hub knows no earlier
    run (it restarted too)."""
    try:
        record = registry.get(hello.vehicle_id)
    except VehicleNotFound:
        return None
    earlier = record.earlier_run(hello.stream_id)
    if earlier is None:
        return None
    run, last_seq = earlier
    since = "" if record.last_seen is None else f" ({now - record.last_seen:.1f} s ago)"
    return (
        f"agent restarted: run {run} ended with sample {last_seq}{since}; no telemetry "
        f"between it and run {hello.stream_id}, which starts now"
    )
