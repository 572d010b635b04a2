"""Flights and state-change events, found in the ordered telemetry stream as it is stored.

The writer sees every vehicle's samples in order, exactly once, so it is where an
arm→disarm pair becomes a flight and a mode change becomes an event; nothing depends on
the agent reporting them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from backend.storage.records import StoredEvent, TelemetryEnvelope

# Hub-derived events are numbered from the sample that caused them, so a batch written
# again after a database error stores each of them once.
EVENT_SLOTS = {"armed": 0, "disarmed": 1, "mode": 2}


@dataclass(frozen=True)
class FlightOpened:
    vehicle_id: str
    time: float


@dataclass(frozen=True)
class FlightClosed:
    vehicle_id: str
    time: float


Transition = FlightOpened | FlightClosed


@dataclass
class BatchPlan:
    """What a batch of samples implies: hub events to store and flights to open or close,
    in stream order."""

    events: list[StoredEvent] = field(default_factory=list)
    transitions: list[Transition] = field(default_factory=list)


@dataclass
class FlightTracker:
    """Armed state and mode per vehicle, and which vehicles have a flight open."""

    armed: dict[str, bool] = field(default_factory=dict)
    mode: dict[str, str] = field(default_factory=dict)
    open_flights: dict[str, int] = field(default_factory=dict)

    def copy(self) -> FlightTracker:
        return FlightTracker(dict(self.armed), dict(self.mode), dict(self.open_flights))

    def plan(self, batch: list[TelemetryEnvelope]) -> BatchPlan:
        plan = BatchPlan()
        for envelope in batch:
            vehicle, sample = envelope.vehicle_id, envelope.telemetry
            state = sample.state
            was_armed = self.armed.get(vehicle)
            if (
                state.armed
                and not was_armed
                and not (was_armed is None and vehicle in self.open_flights)
            ):
                plan.transitions.append(FlightOpened(vehicle, sample.time))
                plan.events.append(_hub_event(envelope, "armed", "armed"))
            elif not state.armed and (
                was_armed or (was_armed is None and vehicle in self.open_flights)
            ):
                plan.transitions.append(FlightClosed(vehicle, sample.time))
                plan.events.append(_hub_event(envelope, "disarmed", "disarmed"))
            self.armed[vehicle] = state.armed
            previous_mode = self.mode.get(vehicle)
            if previous_mode is not None and state.mode != previous_mode:
                text = f"mode {previous_mode} → {state.mode}"
                plan.events.append(_hub_event(envelope, "mode", text))
            self.mode[vehicle] = state.mode
        return plan


def _hub_event(cause: TelemetryEnvelope, kind: str, text: str) -> StoredEvent:
    seq = cause.telemetry.seq * len(EVENT_SLOTS) + EVENT_SLOTS[kind]
    stream = f"hub:{cause.stream_id}"
    return StoredEvent(cause.vehicle_id, stream, seq, cause.telemetry.time, kind, None, text)
