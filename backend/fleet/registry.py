"""The fleet's live state: one record per vehicle, keyed by its identity."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from backend.errors import VehicleNotFound
from backend.fleet.airborne import TakeoffClock
from protocol.messages import Hello, Telemetry, VehicleState, VehicleSummary
from protocol.photos import CameraIntrinsics

if TYPE_CHECKING:
    from backend.fleet.commands import AgentChannel


class KnownVehicle(Protocol):
    """A vehicle as stored by an earlier run (the store's vehicle row is one); the live
    state is plain data and imports nothing of the store."""

    @property
    def id(self) -> str: ...

    @property
    def autopilot(self) -> str: ...

    @property
    def vehicle_type(self) -> str: ...

    @property
    def modes(self) -> str: ...  # comma-separated

    @property
    def system_id(self) -> int: ...

    @property
    def last_seen(self) -> float: ...


# The telemetry rate on /metrics: frames over the last 5 s; an agent sends 10 a second.
RATE_WINDOW_S = 5.0
RATE_MAX_FRAMES = 1000  # 200 frames a second over the window, far beyond any agent


@dataclass
class VehicleRecord:
    id: str
    autopilot: str
    vehicle_type: str
    modes: list[str]
    system_id: int = 1
    last_seen: float | None = None
    state: VehicleState | None = None
    # Highest telemetry number seen per agent stream: older samples do not move the
    # live state backwards (storage has its own, gap-aware bookkeeping).
    last_seq: dict[str, int] = field(default_factory=dict)
    # The stamp of a `LiveState` the live view shows ahead of a replaying backlog: until a
    # sample at least that recent arrives, samples are the backlog's and are only stored.
    # Samples are otherwise ordered by their numbers, never their stamps: the agent's
    # clock may step back (time sync after boot) and the view must not freeze until
    # the clock catches up.
    live_ahead_at: float | None = None
    # When this hub received the vehicle's latest telemetry frames (monotonic seconds), for
    # its rate on /metrics: at most RATE_MAX_FRAMES, so memory stays bounded at any rate.
    frame_times: deque[float] = field(
        default_factory=lambda: deque(maxlen=RATE_MAX_FRAMES), repr=False, compare=False
    )
    # The connected agent's command channel, None while no agent is connected: the one
    # record of whether the vehicle is online (commands go down this channel).
    channel: AgentChannel | None = field(default=None, repr=False, compare=False)
    # The camera its agent uploads photos from, as its latest hello said (None: no camera,
    # or not known: an agent that has not connected to this hub since it started).
    camera: CameraIntrinsics | None = None
    # When it took off, from the states it reported in order (sent to browsers, so a
    # reloaded page shows the flight's own time, not the time since the page loaded).
    takeoff: TakeoffClock = field(default_factory=TakeoffClock, repr=False, compare=False)

    @property
    def connected(self) -> bool:
        return self.channel is not None

    def count_frame(self, now: float) -> None:
        """A new telemetry sample moved the live state (``now``: monotonic)."""
        self.frame_times.append(now)

    def telemetry_rate(self, now: float) -> float:
        """Frames per second received over the last RATE_WINDOW_S."""
        since = now - RATE_WINDOW_S
        return sum(1 for at in self.frame_times if at > since) / RATE_WINDOW_S

    def earlier_run(self, stream_id: str) -> tuple[str, int] | None:
        """The agent run this vehicle's live state came from last, and its last sample's
        number, when that run is not ``stream_id``: the agent restarted (a crash, a power
        cycle). None for the same run reconnecting, or nothing seen since the hub started."""
        if not self.last_seq:
            return None
        run = next(reversed(self.last_seq))  # runs are added in the order they connected
        return None if run == stream_id else (run, self.last_seq[run])

    def summary(self) -> VehicleSummary:
        return VehicleSummary(
            id=self.id,
            autopilot=self.autopilot,
            vehicle_type=self.vehicle_type,
            modes=self.modes,
            connected=self.connected,
            last_seen=self.last_seen,
            airborne_since=self.takeoff.airborne_since,
            state=self.state,
        )


class FleetRegistry:
    def __init__(self) -> None:
        self._vehicles: dict[str, VehicleRecord] = {}

    def __len__(self) -> int:
        return len(self._vehicles)

    def load(self, rows: Iterable[KnownVehicle]) -> None:
        """Vehicles known from earlier runs, offline until their agent connects."""
        for row in rows:
            self._vehicles[row.id] = VehicleRecord(
                id=row.id,
                autopilot=row.autopilot,
                vehicle_type=row.vehicle_type,
                modes=[mode for mode in row.modes.split(",") if mode],
                system_id=row.system_id,
                last_seen=row.last_seen,
            )

    def get(self, vehicle_id: str) -> VehicleRecord:
        try:
            return self._vehicles[vehicle_id]
        except KeyError:
            raise VehicleNotFound(vehicle_id) from None

    def all(self) -> list[VehicleRecord]:
        return sorted(self._vehicles.values(), key=lambda record: record.id)

    def connect(self, hello: Hello, channel: AgentChannel) -> VehicleRecord:
        """The vehicle is online through `channel`, which replaces any earlier agent's."""
        record = self._vehicles.get(hello.vehicle_id)
        if record is None:
            record = VehicleRecord(
                id=hello.vehicle_id,
                autopilot=hello.autopilot,
                vehicle_type=hello.vehicle_type,
                modes=list(hello.modes),
                system_id=hello.system_id,
                camera=hello.camera,
            )
            self._vehicles[record.id] = record
        else:
            record.autopilot = hello.autopilot
            record.vehicle_type = hello.vehicle_type
            record.modes = list(hello.modes)
            record.system_id = hello.system_id
        record.camera = hello.camera
        record.channel = channel
        # A new connection sends its own live state if it is behind again.
        record.live_ahead_at = None
        return record

    def mirror(
        self, summary: VehicleSummary, remote: Callable[[], AgentChannel]
    ) -> VehicleRecord | None:
        """Another hub's word on a vehicle whose agent it holds (several hubs): the
        vehicle as it is there, reached through ``remote()`` (a channel made once per
        vehicle) while that hub says it is connected. None, and nothing changes, when
        this hub holds the vehicle's agent itself: its own link is the truth."""
        record = self._vehicles.get(summary.id)
        if record is not None and record.channel is not None and not record.channel.remote:
            return None
        if record is None:
            record = VehicleRecord(
                id=summary.id,
                autopilot=summary.autopilot,
                vehicle_type=summary.vehicle_type,
                modes=list(summary.modes),
            )
            self._vehicles[summary.id] = record
        record.autopilot = summary.autopilot
        record.vehicle_type = summary.vehicle_type
        record.modes = list(summary.modes)
        record.last_seen = summary.last_seen
        record.state = summary.state
        record.takeoff.airborne_since = summary.airborne_since
        if not summary.connected:
            record.channel = None
        elif record.channel is None:
            record.channel = remote()
        return record

    def disconnect(self, vehicle_id: str, channel: AgentChannel) -> VehicleRecord | None:
        """The agent behind `channel` is gone: the record, now offline, or None when a
        newer agent had already taken the vehicle over (it stays online)."""
        record = self.get(vehicle_id)
        if record.channel is not channel:
            return None
        record.channel = None
        return record

    def set_modes(self, vehicle_id: str, modes: list[str]) -> VehicleRecord:
        """The modes the vehicle's autopilot listed, in place of its hello's."""
        record = self.get(vehicle_id)
        record.modes = list(modes)
        return record

    def apply_live(self, vehicle_id: str, time: float, state: VehicleState) -> bool:
        """The agent's state now, sent ahead of a replayed backlog; older samples that
        arrive after it are stored but no longer move the live state."""
        record = self.get(vehicle_id)
        record.live_ahead_at = time
        record.state = state
        record.last_seen = time
        record.takeoff.observe(state, time)
        return True

    def apply(self, vehicle_id: str, stream_id: str, telemetry: Telemetry) -> bool:
        """Take a sample into live state; False if it is not newer than what the live
        state already shows (a replayed backlog behind a `LiveState`, a duplicate)."""
        record = self.get(vehicle_id)
        if telemetry.seq <= record.last_seq.get(stream_id, -1):
            return False
        record.last_seq[stream_id] = telemetry.seq
        if record.live_ahead_at is not None:
            if telemetry.time < record.live_ahead_at:
                return False
            record.live_ahead_at = None  # caught up: numbers order the samples again
        record.state = telemetry.state
        record.last_seen = telemetry.time
        record.takeoff.observe(telemetry.state, telemetry.time)
        return True
