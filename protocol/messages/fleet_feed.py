"""Hub -> clients: the fleet snapshot a connection starts with and the batches of vehicles
that changed."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import ConfigDict, Field

from protocol.messages.base import MAX_FLEET, MAX_MODES, Message, Name, VehicleId
from protocol.messages.vehicle_state import VehicleState

_AIRBORNE_SINCE = (
    "Unix time (the vehicle's telemetry clock) of its take-off: the first sample in which "
    "it flew (armed, landed_state takeoff/in_air/landing) after one in which it was on "
    "the ground. Null while it is on the ground, and while the hub has not seen it take "
    "off (it was already flying when the hub first heard from it): unknown, never zero."
)


class VehicleSummary(Message):
    id: VehicleId
    autopilot: Name
    vehicle_type: Name
    modes: list[Name] = Field(max_length=MAX_MODES)
    connected: bool
    last_seen: float | None = Field(default=None, description="Unix time of the last telemetry.")
    airborne_since: float | None = Field(default=None, description=_AIRBORNE_SINCE)
    state: VehicleState | None = None


def _unchanged(value: object) -> bool:
    return value is None


# What a vehicle's agent says once, in its hello, and what therefore does not change while
# it stays connected: a live update leaves it out unless it changed.
_SAID_ONCE = (
    "Left out when this feed has already sent it and it has not changed since: keep the "
    "value from the fleet snapshot or an earlier update."
)
_SAID_ONCE_FIELDS = ("autopilot", "vehicle_type", "modes")


def _said_once_schema(schema: dict[str, Any]) -> None:
    """On the wire these fields are a value or absent, never null: say so in the schema
    (the dashboard's types are generated from it)."""
    for name in _SAID_ONCE_FIELDS:
        field = schema["properties"][name]
        del field["default"]
        field.update(next(kind for kind in field.pop("anyOf") if kind.get("type") != "null"))


class VehicleChange(Message):
    """One vehicle's live update. It carries ``autopilot``, ``vehicle_type`` and ``modes``
    (a third of the frame, ten times a second) only the first time this connection shows
    the vehicle and when they change (its agent reconnected with another hello, or sent
    the autopilot's own mode list); the fleet
    snapshot a new connection starts with always has them."""

    model_config = ConfigDict(json_schema_extra=_said_once_schema)

    id: VehicleId
    autopilot: Name | None = Field(default=None, exclude_if=_unchanged, description=_SAID_ONCE)
    vehicle_type: Name | None = Field(default=None, exclude_if=_unchanged, description=_SAID_ONCE)
    modes: list[Name] | None = Field(
        default=None, max_length=MAX_MODES, exclude_if=_unchanged, description=_SAID_ONCE
    )
    connected: bool
    last_seen: float | None = Field(default=None, description="Unix time of the last telemetry.")
    airborne_since: float | None = Field(default=None, description=_AIRBORNE_SINCE)
    state: VehicleState | None = None


class FleetSnapshot(Message):
    type: Literal["fleet"] = "fleet"
    vehicles: list[VehicleSummary] = Field(max_length=MAX_FLEET)


class VehicleBatch(Message):
    """The vehicles that changed since this connection's last batch, each once (its newest
    state): one frame per tick for the whole fleet, not one per vehicle. A vehicle's state
    goes out at most once per the hub's ``ui_update_interval_s``; a client that reads too
    slowly gets the newest state of each vehicle when it catches up, never a backlog."""

    type: Literal["vehicles"] = "vehicles"
    vehicles: list[VehicleChange] = Field(max_length=MAX_FLEET)
