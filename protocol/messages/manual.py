"""Manual control (browser -> hub -> agent): the lease a pilot asks for, stick frames, and
the echoes that give the pilot the round trip."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from protocol.messages.base import MAX_NAME_CHARS, MAX_SEQ, Message, MessageText, VehicleId
from protocol.messages.params import ParamFix

# MAVLink MANUAL_CONTROL's ranges: x (pitch, forward +), y (roll, right +) and r (yaw,
# clockwise +) in [-1000, 1000]; z (throttle or climb) in [0, 1000], 500 at mid stick.
StickAxis = Annotated[int, Field(ge=-1000, le=1000)]
ThrottleAxis = Annotated[int, Field(ge=0, le=1000)]


class ManualAxes(Message):
    x: StickAxis = Field(description="pitch: forward positive, -1000..1000")
    y: StickAxis = Field(description="roll: right positive, -1000..1000")
    z: ThrottleAxis = Field(default=500, description="throttle or climb: 0..1000, 500 mid")
    r: StickAxis = Field(default=0, description="yaw: clockwise positive, -1000..1000")
    buttons: int = Field(default=0, ge=0, le=65535, description="MANUAL_CONTROL buttons")


class ControlRequest(Message):
    """Ask for (or give back) the manual-control lease of one vehicle. Needs the
    'command' permission; one pilot per vehicle. An acquire is granted (a `lease` naming
    the holder, to every client) only once the vehicle's agent has checked that the
    autopilot takes MANUAL_CONTROL from it and switched to its pilot mode; otherwise
    a `lease_refused` gives the reason (e.g. SYSID_MYGCS or COM_RC_IN_MODE) and, where
    a parameter is the reason, the change that would lift it. Release and revoke put
    the vehicle in its hold mode."""

    type: Literal["control"] = "control"
    vehicle_id: VehicleId
    action: Literal["acquire", "release", "revoke"] = Field(
        description="revoke: an admin ends whoever's lease"
    )


# Where a frame's values come from. The agent holds the vehicle when a "gamepad" or
# "program" stream repeats the same off-centre values for its frozen time (a frozen
# device, or a client streaming its last reading); an on-screen stick or a key held
# still is a pilot holding a steady input, and the page's own liveness (hidden, blurred,
# pointer lost) stops those streams.
InputSource = Literal["gamepad", "touch", "keyboard", "program"]


class ManualInput(Message):
    """One frame of stick input, sent by the lease holder at 25 Hz or more. Frames from
    a client without the lease, with a seq not newer than the last, or faster than
    100 Hz are refused and never forwarded; the newest frame wins."""

    type: Literal["manual"] = "manual"
    vehicle_id: VehicleId
    seq: int = Field(ge=0, le=MAX_SEQ)
    axes: ManualAxes
    source: InputSource = Field(
        default="program",
        description="gamepad and program streams that repeat the same off-centre values "
        "for 3 s count as frozen and hold the vehicle; touch and keyboard do not",
    )
    sent_ms: float | None = Field(
        default=None,
        ge=0,
        le=1e15,
        description="the client's own clock when it read the input (ms); the agent "
        "echoes it (manual_echo) so the pilot sees the input-to-vehicle round trip",
    )


class LeaseState(Message):
    """Who flies a vehicle by hand now (holder None: nobody), sent to every client when
    it changes, and for every vehicle with a lease history when a client connects. A
    lease ends when released, revoked by an admin, expired (no input for 2 s), on the
    vehicle (the agent's deadman, frozen input, its hold button, a mode change from the
    RC transmitter or another GCS), or with a hub restart; `reason` says which."""

    type: Literal["lease"] = "lease"
    vehicle_id: VehicleId
    holder: str | None = Field(default=None, max_length=200)
    reason: str = Field(default="", max_length=200)
    resume_mode: str | None = Field(
        default=None,
        max_length=MAX_NAME_CHARS,
        description="a mission was in progress when the lease began and is paused: "
        "set this mode to resume it (ArduPilot AUTO, PX4 MISSION)",
    )


class LeaseRefusal(Message):
    """A `control` request refused, to the client that sent it: the reason in words (the
    autopilot's setup, another pilot, the vehicle offline, ...), and where the vehicle's
    setup is the reason, the parameter change that would lift it. Every dashboard also
    sees the refusal in its event feed (a hub event of kind "control")."""

    type: Literal["lease_refused"] = "lease_refused"
    vehicle_id: VehicleId
    action: Literal["acquire", "release", "revoke"]
    reason: MessageText
    fix: ParamFix | None = None


class ManualFrame(Message):
    """Stick input relayed to the agent; the agent holds the vehicle when these stop."""

    type: Literal["manual"] = "manual"
    seq: int = Field(ge=0, le=MAX_SEQ)
    axes: ManualAxes
    source: InputSource = "program"
    sent_ms: float | None = Field(default=None, ge=0, le=1e15)


class ManualApplied(Message):
    """The agent sent this frame to the flight controller as MANUAL_CONTROL (about twice
    a second while a stream lasts): the hub passes it to the lease holder."""

    type: Literal["manual_applied"] = "manual_applied"
    seq: int = Field(ge=0, le=MAX_SEQ)
    sent_ms: float | None = Field(default=None, ge=0, le=1e15)


class ManualEcho(Message):
    """To the lease holder: its frame ``seq`` went out to the flight controller. Its
    ``sent_ms`` against the client's clock now is the input-to-vehicle round trip."""

    type: Literal["manual_echo"] = "manual_echo"
    vehicle_id: VehicleId
    seq: int = Field(ge=0, le=MAX_SEQ)
    sent_ms: float | None = Field(default=None, ge=0, le=1e15)
