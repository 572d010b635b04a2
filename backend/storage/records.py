"""What flows from the realtime path into storage."""

from __future__ import annotations

from dataclasses import dataclass

from protocol.messages import Photo, SequencedKind, Telemetry


@dataclass(frozen=True)
class TelemetryEnvelope:
    """A telemetry message with the identity the hub knows it under."""

    vehicle_id: str
    stream_id: str
    telemetry: Telemetry


@dataclass(frozen=True)
class StoredEvent:
    vehicle_id: str
    stream_id: str  # the agent's stream, or "hub" for events the hub derives
    seq: int | None  # None for the hub's own events
    time: float
    kind: str
    severity: int | None
    text: str
    mission_item: int | None = None
    # A camera event's photo: on the live feed and to the survey's progress; the stored
    # row keeps it in the text.
    photo: Photo | None = None


@dataclass(frozen=True)
class LostFrames:
    """Frames an agent said it no longer has (its bounded outbox dropped them), or that the
    hub refused (``refused``: a telemetry sample with an impossible value)."""

    vehicle_id: str
    stream_id: str
    kind: SequencedKind
    first_seq: int
    last_seq: int
    reason: str
    refused: bool = False


StoredRecord = TelemetryEnvelope | StoredEvent | LostFrames
