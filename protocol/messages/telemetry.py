"""Agent -> hub: its hello, its numbered telemetry and its live state, its mode list, and
its scan source's counters."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from protocol.messages.base import (
    MAX_CAPABILITIES,
    MAX_MODES,
    MAX_SEQ,
    MAX_UNIX_TIME,
    Message,
    Name,
    StreamId,
    VehicleId,
)
from protocol.messages.delivery import ReplayedStream
from protocol.messages.vehicle_state import VehicleState
from protocol.photos import CameraIntrinsics


class Hello(Message):
    """First frame from an agent: who it is and what it can do."""

    type: Literal["hello"] = "hello"
    protocol: int
    vehicle_id: VehicleId
    autopilot: Name = Field(description="ardupilot, px4 or generic")
    vehicle_type: Name = Field(description="multirotor, rover, fixed_wing, ...")
    system_id: int = Field(ge=1, le=255)
    modes: list[Name] = Field(
        default_factory=list, max_length=MAX_MODES, description="Mode names set_mode accepts."
    )
    capabilities: list[Name] = Field(default_factory=list, max_length=MAX_CAPABILITIES)
    agent_version: Name
    stream_id: StreamId = Field(
        description="Names this agent run's sequence counters, and the run itself: a new "
        "hello from the same run replaces its stale connection, one from another run is "
        "refused while the first still answers (close 4409)."
    )
    camera: CameraIntrinsics | None = Field(
        default=None,
        description="The camera whose photos this agent uploads (its --camera-model), so "
        "that the hub offers it as a survey preset and refuses, before take-off, a survey "
        "planned for another camera; null when the agent has no camera.",
    )


class Telemetry(Message):
    type: Literal["telemetry"] = "telemetry"
    stream_id: ReplayedStream = None
    seq: int = Field(ge=0, le=MAX_SEQ)
    time: float = Field(ge=0, le=MAX_UNIX_TIME, description="Unix time of the snapshot, seconds.")
    state: VehicleState


class LiveState(Message):
    """The vehicle's state now, ahead of a backlog being replayed: for the live view only,
    never stored. While an agent catches up after an outage its numbered telemetry is
    minutes old; this keeps the map showing where the vehicle is, not where it was."""

    type: Literal["live_state"] = "live_state"
    time: float = Field(ge=0, le=MAX_UNIX_TIME, description="Unix time of the snapshot, seconds.")
    state: VehicleState


MAX_SOURCE_COUNTS = 32


class ScanSourceStats(Message):
    """The agent's scan source (its LIDAR's parser): what it decoded and what it threw
    away, by reason, since the agent started. Sent when the counts change, every few
    seconds at most; the hub shows the latest in the vehicle's scan diagnostics (never
    stored), so an empty scan comes with a reason."""

    type: Literal["scan_source_stats"] = "scan_source_stats"
    source: Name = Field(description="the LIDAR model (rplidar-a1, ld06, ...), mavlink or ros2")
    counts: dict[Name, Annotated[int, Field(ge=0, le=2**53)]] = Field(
        max_length=MAX_SOURCE_COUNTS,
        description="packets, points, responses, and dropped_<reason> (bad_checksum, "
        "noise_bytes, ...) for a serial LIDAR; each source's own counters otherwise",
    )


class ModeList(Message):
    """The vehicle's modes as its autopilot reports them (MAVLink AVAILABLE_MODES: PX4
    from 1.15, ArduPilot from 4.7), sent when the agent has read the list after its hello
    and whenever the autopilot says it changed (AVAILABLE_MODES_MONITOR). It replaces the
    hello's ``modes``, which were the agent's fixed table for the autopilot until then."""

    type: Literal["modes"] = "modes"
    modes: list[Name] = Field(
        max_length=MAX_MODES,
        description="Mode names set_mode accepts, as the autopilot lists them.",
    )
