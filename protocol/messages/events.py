"""Events: an agent's numbered events for the flight log (with a camera's photo), and the
batches of live events the hub sends its clients."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from protocol.messages.base import MAX_SEQ, MAX_UNIX_TIME, Message, Name, VehicleId
from protocol.messages.delivery import ReplayedStream

EventKind = Literal[
    "statustext",
    "mode",
    "armed",
    "disarmed",
    "link_up",
    "link_down",
    "failsafe",
    "mission",
    "id_clash",  # the hub refused a second agent for this vehicle id (never sent by agents)
    "manual",  # browser manual control started, ended or held by the deadman
    "upload",  # the agent's onboard .tlog could not be handed over (or was, after failing)
    "camera",  # the camera fired (CAMERA_FEEDBACK; PX4: CAMERA_TRIGGER); its photo says where
    "formation",  # a follower joined, held, backed off or left its formation
]
# The kinds the hub itself records in a vehicle's flight log, beside its agent's.
HubEventKind = Literal[
    "command",  # a command sent to the vehicle, with its answer
    "data_lost",  # samples or events the agent no longer had, or the hub refused
    "agent_restart",  # the vehicle's agent came back as a new process
    "obstacle",  # the LIDAR map found an obstacle on the vehicle's path
    "id_clash",
    "link_up",
    "link_down",
    "manual",
]
StoredEventKind = Literal[EventKind, HubEventKind]  # one flat list (typing flattens it)


class Photo(Message):
    """Where and when a photo was taken, as the autopilot reports it (ArduPilot's
    CAMERA_FEEDBACK; PX4's CAMERA_TRIGGER, posed from the streams at its arrival)."""

    index: int = Field(ge=0, le=2**32 - 1, description="the camera's image number (img_idx)")
    lat: float = Field(ge=-90, le=90)
    lon: float = Field(ge=-180, le=180)
    alt_rel: float = Field(ge=-1000, le=10000, description="metres above home")


class Event(Message):
    """Something that happened, for the flight log: a STATUSTEXT, a failsafe, ...

    Events are stored like telemetry (at least once, de-duplicated by ``(stream_id, seq)``),
    with their own sequence numbers."""

    type: Literal["event"] = "event"
    stream_id: ReplayedStream = None
    seq: int = Field(ge=0, le=MAX_SEQ)
    time: float = Field(ge=0, le=MAX_UNIX_TIME, description="Unix time, seconds.")
    kind: EventKind
    severity: int | None = Field(
        default=None, ge=0, le=7, description="MAV_SEVERITY: 0 emergency .. 7 debug"
    )
    text: str = Field(max_length=500)
    mission_item: int | None = Field(
        default=None,
        ge=0,
        le=65535,
        description="the mission item a 'mission' event is about (numbered as the hub does)",
    )
    photo: Photo | None = Field(default=None, description="for a 'camera' event: the photo")


# A batch of live events stays well inside a frame: an event is at most about 800 bytes.
MAX_LIVE_EVENTS = 64


class LiveEvent(Message):
    """An event as the live feed carries it: the agent's (a STATUSTEXT, a mode change, a
    failsafe, ...) or the hub's own (a link up or down, a command's result)."""

    vehicle_id: VehicleId
    time: float = Field(ge=0, le=MAX_UNIX_TIME, description="Unix time, seconds.")
    kind: Name = Field(
        description="an agent's event kind, or one of the hub's: command, data_lost, ..."
    )
    severity: int | None = Field(
        default=None, ge=0, le=7, description="MAV_SEVERITY: 0 emergency .. 7 debug"
    )
    text: str = Field(max_length=500)
    mission_item: int | None = Field(default=None, ge=0, le=65535)
    photo: Photo | None = Field(default=None, description="for a 'camera' event: the photo")
    repeat: int = Field(
        default=1,
        ge=1,
        description="how many identical events (same vehicle, kind, severity and text) "
        "this one stands for: repeats within one batch are sent once; time is the newest",
    )


class EventBatch(Message):
    """The events since the last batch, oldest first: at most one batch every
    GCS_UI_UPDATE_INTERVAL_S. A client that reads too slowly loses the least severe events
    first; ``dropped`` says how many."""

    type: Literal["events"] = "events"
    events: list[LiveEvent] = Field(max_length=MAX_LIVE_EVENTS)
    dropped: int = Field(
        default=0, ge=0, description="events left out since the last batch: the queue was full"
    )
