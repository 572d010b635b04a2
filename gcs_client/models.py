"""The hub's REST bodies and answers and the live feed's messages, as pydantic models.

GENERATED FILE - DO NOT EDIT. Written by scripts/gen_client_models.py from the hub's
OpenAPI document and the wire protocol's JSON Schema (tests/unit/gcs_client/test_client_models.py
checks it is in step with them). Lenient by design: no bounds (the hub checks those and
says what it refused), and fields a newer hub adds are kept, not refused.
"""

# ruff: noqa: E501

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter


class Model(BaseModel):
    """Every generated model: unknown fields kept, fields settable by name or alias."""

    model_config = ConfigDict(extra="allow", populate_by_name=True)


class AccessToken(Model):
    access_token: str
    token_type: str = Field(default="bearer")
    expires_in: int


class AgentToken(Model):
    id: int
    vehicle_id: str
    created_at: float
    created_by: str
    revoked: bool


class ApiToken(Model):
    id: int
    name: str
    scopes: list[str]
    created_at: float
    expires_at: float | None
    revoked: bool


class ApiTokenRequest(Model):
    name: str
    scopes: list[Literal["read", "command", "audit", "admin"]] | None = Field(
        default=None, description="Permissions to keep (a subset of the role's); all if unset"
    )
    expires_in_days: int | None = Field(
        default=90,
        description="Days until the token expires, 1 to 3,650 (90 if not given); null: it never expires (revoke it when it is no longer needed)",
    )


class ArmCommand(Model):
    name: Literal["arm"] = Field(default="arm")


AuditAction = Literal[
    "login",
    "logout",
    "token.create",
    "token.revoke",
    "user.create",
    "user.update",
    "agent_token.create",
    "agent_token.revoke",
    "rails.update",
    "rails.clear",
    "command",
    "control.lease",
    "formation.start",
    "formation.change",
    "formation.stop",
    "denied",
]


class AuditPage(Model):
    entries: list[AuditRecord]
    next_before_id: int | None = Field(
        description="Pass as before_id for the next (older) page; null on the last page"
    )


class AuditRecord(Model):
    id: int
    time: float
    actor: str = Field(description="The user (or agent:<vehicle>, provisioning, anonymous)")
    role: str
    source: str = Field(description="The client's address")
    action: AuditAction
    target: str
    outcome: str = Field(description="ok, refused, failed or denied")
    detail: dict[str, Any]
    token_kind: Literal["session", "access", "api", "agent"] | None = Field(
        default=None,
        description="The credential the actor used: a dashboard session, an access token (/auth/token), an API token or an agent token; null for anonymous attempts, the hub itself, and entries from before it was recorded",
    )
    token_id: int | None = Field(
        default=None,
        description="That token's id (an API token's as in /auth/api-tokens, an agent token's as in /agent-tokens)",
    )
    token: str | None = Field(
        default=None,
        description="An API token's name, so an integration's acts are told from its user's",
    )


class BatteryEstimateModel(Model):
    distance_m: float = Field(description="Horizontal distance including the return home")
    flight_time_s: float
    required_pct: float = Field(description="Battery the flight needs, percent of capacity")
    available_pct: float | None = Field(description="Battery remaining now; null if unknown")


class Body_token_api_v1_auth_token_post(Model):
    grant_type: str | None = Field(default=None)
    username: str
    password: str
    scope: str = Field(default="")
    client_id: str | None = Field(default=None)
    client_secret: str | None = Field(default=None)


class CameraModel(Model):
    sensor_width_mm: float
    sensor_height_mm: float
    image_width_px: int
    image_height_px: int
    focal_length_mm: float
    landscape: bool = Field(default=True)
    distance_trigger: bool = Field(default=True)


class CameraPreset(Model):
    """A camera a survey may name by ``id`` (its ``camera.preset``), with its figures."""

    id: str
    name: str
    sensor_width_mm: float
    sensor_height_mm: float
    image_width_px: int
    image_height_px: int
    focal_length_mm: float
    distance_trigger: bool = Field(description="False: one DO_DIGICAM_CONTROL per photo")
    vehicle_ids: list[str] | None = Field(
        default=None,
        description="The vehicles whose agents carry this camera (a `fleet:` preset); empty for a catalogue camera",
    )


class ChangeSpeedCommand(Model):
    name: Literal["change_speed"] = Field(default="change_speed")
    speed: float = Field(description="m/s")
    speed_type: Literal["ground", "air"] = Field(default="ground")


class ClientConfig(Model):
    basemap_url: str | None = Field(description="the online street map (XYZ); None: off")
    basemap_attribution: str
    basemap_max_zoom: int
    imagery_url: str | None = Field(default=None, description="online imagery (XYZ); None: off")
    imagery_attribution: str = Field(default="")
    imagery_max_zoom: int = Field(default=19)
    protocol: int


class CommandOutcome(Model):
    """What the flight controller answered, in words an operator can act on."""

    status: Literal["accepted", "refused", "timeout", "failed"]
    result: str | None = Field(
        default=None, description="The MAV_RESULT name from COMMAND_ACK, when there was one."
    )
    message: str
    values: dict[str, float] | None = Field(
        default=None, description="Parameter values, for the parameter commands."
    )
    items: list[MissionItem] | None = Field(
        default=None, description="The vehicle's mission, for a mission download (home first)."
    )
    fix: ParamFix | None = Field(
        default=None,
        description="A refusal the vehicle's setup causes: the parameter change that would lift it (e.g. SYSID_MYGCS for manual control)",
    )
    param_meta: ParamMeta | None = Field(
        default=None,
        description="For param_get and param_set: the parameter's metadata, when the autopilot publishes it (PX4); absent, its range was not checked.",
    )


class CommandPage(Model):
    commands: list[CommandRecord]
    next_before_id: int | None


class CommandRecord(Model):
    id: int
    time: float
    vehicle_id: str
    actor: str
    name: str
    command: dict[str, Any] = Field(description='The command as sent, e.g. {"name": "land"}')
    status: str
    result: str | None
    message: str


class CommandResponse(Model):
    vehicle_id: str
    command: (
        ArmCommand
        | DisarmCommand
        | TakeoffCommand
        | LandCommand
        | ReturnToLaunchCommand
        | SetModeCommand
        | GotoCommand
        | HoldCommand
        | ChangeSpeedCommand
        | SetHomeCommand
        | RebootCommand
        | ParamListCommand
        | ParamGetCommand
        | ParamSetCommand
        | MissionUploadCommand
        | MissionDownloadCommand
        | MissionClearCommand
        | MissionSetCurrentCommand
        | ManualStartCommand
        | ManualStopCommand
    )
    outcome: CommandOutcome


class ControlRequest(Model):
    """Ask for (or give back) the manual-control lease of one vehicle. Needs the
    'command' permission; one pilot per vehicle. An acquire is granted (a `lease` naming
    the holder, to every client) only once the vehicle's agent has checked that the
    autopilot takes MANUAL_CONTROL from it and switched to its pilot mode; otherwise
    a `lease_refused` gives the reason (e.g. SYSID_MYGCS or COM_RC_IN_MODE) and, where
    a parameter is the reason, the change that would lift it. Release and revoke put
    the vehicle in its hold mode."""

    type: Literal["control"] = Field(default="control")
    vehicle_id: str
    action: Literal["acquire", "release", "revoke"] = Field(
        description="revoke: an admin ends whoever's lease"
    )


Controller = Literal["leader_follower", "consensus"]


class CurrentItem(Model):
    seq: int


class DisarmCommand(Model):
    name: Literal["disarm"] = Field(default="disarm")
    force: bool = Field(default=False, description="Disarm even in flight (motors stop).")


class DronePhotos(Model):
    vehicle_id: str
    received: int = Field(description="photos stored")
    failed: int = Field(description="photos refused")
    reasons: dict[str, int] = Field(description="refusals by reason code")


class DroneRun(Model):
    vehicle_id: str
    state: DroneState = Field(default="assigned")
    items: list[MissionItem]
    lanes: list[LaneRecord]
    lanes_done_before: int = Field(default=0)
    photos: list[tuple[float, float]] | None = Field(default=None, description="[lat, lon]")
    photo_indexes: list[int] | None = Field(default=None)
    current: int | None = Field(default=None)
    airborne: bool = Field(default=False)
    armed_seen: bool = Field(default=False)
    reason: str | None = Field(default=None)
    finished: float | None = Field(default=None)


DroneState = Literal["assigned", "flying", "done", "dropped"]


class ErrorMessage(Model):
    """Every error but a 422: one sentence that names what went wrong."""

    detail: str


class ErrorReply(Model):
    """Sent to a peer whose frame could not be used; the connection stays open."""

    type: Literal["error"] = Field(default="error")
    code: Literal[
        "bad_frame", "invalid_message", "unexpected_message", "too_many_errors", "forbidden"
    ]
    message: str


class ErrorStatsModel(Model):
    samples: int = Field(description="Follower reports measured")
    rms_xy_m: float
    max_xy_m: float
    rms_z_m: float
    max_z_m: float


class EventBatch(Model):
    """The events since the last batch, oldest first: at most one batch every
    GCS_UI_UPDATE_INTERVAL_S. A client that reads too slowly loses the least severe events
    first; ``dropped`` says how many."""

    type: Literal["events"] = Field(default="events")
    events: list[LiveEvent]
    dropped: int = Field(
        default=0, description="events left out since the last batch: the queue was full"
    )


class EventPage(Model):
    events: list[EventRecord]
    next_before_id: int | None


class EventRecord(Model):
    id: int
    vehicle_id: str
    time: float
    kind: str
    severity: int | None
    text: str
    mission_item: int | None = Field(default=None)


class FleetSnapshot(Model):
    type: Literal["fleet"] = Field(default="fleet")
    vehicles: list[VehicleSummary]


class Flight(Model):
    id: int
    vehicle_id: str
    start_time: float
    end_time: float | None
    duration_s: float | None
    distance_m: float | None
    max_alt_m: float | None
    battery_used_pct: float | None
    samples: int | None


class FlightPage(Model):
    flights: list[Flight]
    next_before_id: int | None


class FlightTelemetry(Model):
    flight_id: int
    vehicle_id: str
    samples: list[Sample]


class FollowerModel(Model):
    vehicle_id: str
    offset: OffsetModel | None = Field(
        default=None, description="Its slot; null takes the next slot of the shape preset"
    )
    up: float = Field(default=0.0, description="Metres above the leader in a preset slot")
    neighbours: list[str] | None = Field(
        default=None,
        description="Consensus: the followers it hears (its communication graph's edges, weight 1); null hears every other follower",
    )


class FormationRequest(Model):
    leader_id: str | None = Field(
        default=None, description="The leading vehicle; null for a virtual leader"
    )
    route: list[RoutePoint]
    speed_ms: float = Field(description="The leader's speed along the route")
    pause_s: float = Field(default=0.0, description="Pause at each waypoint")
    followers: list[FollowerModel]
    shape: Shape = Field(default="wedge")
    spacing_m: float = Field(default=3.0)
    min_separation_m: float = Field(
        default=2.0, description="No two vehicles ever closer than this"
    )
    obstacle_clearance_m: float = Field(
        default=2.0,
        description="A follower whose slot comes this close (horizontally) to a point of the leader's LIDAR scans holds short of it; 0 turns the check off",
    )
    controller: Controller = Field(
        default="leader_follower",
        description="leader_follower: each follower flies its slot around the leader; consensus: also agrees with its neighbours on where the leader is",
    )
    k_leader: float = Field(default=1.0, description="Consensus: leader weight")
    k_neighbour: float = Field(default=0.5, description="Consensus: weight of each neighbour")


class FormationStatus(Model):
    id: str
    leader_id: str | None = Field(description="Null for a virtual leader")
    slots: dict[str, OffsetModel] = Field(description="Each follower's slot")
    started_at: float = Field(description="Unix time the formation started")
    formed_at: float | None = Field(
        description="Unix time every follower reached its slot and the route's clock started; null while they join"
    )
    route_duration_s: float = Field(description="The route's length in the fleet's seconds")
    state: Literal["joining", "flying", "route_done", "stopped"] = Field(
        description="joining: the followers make for their slots; flying: the leader flies the route; route_done: it reached the route's last waypoint and the formation holds there until stopped; stopped: ended (see `stopped`)"
    )
    route_done_at: float | None = Field(
        description="Unix time the leader reaches the route's last waypoint (in the future while flying); null while joining, or when it stopped before the end"
    )
    controller: Controller
    tracking: dict[str, TrackingModel] = Field(
        description="Each follower's error from its slot (the leader carried to the time of the follower's report): live, and RMS and maximum per leg and over the mission"
    )
    stopped: str | None = Field(description="Why it stopped; null while it flies")


class GeoJsonPolygon(Model):
    type: Literal["Polygon"] = Field(default="Polygon")
    coordinates: list[list[list[float]]] = Field(
        description="[longitude, latitude] rings: the outline first, then holes (no-fly areas)"
    )


class GeoPointModel(Model):
    lat: float = Field(description="Latitude, degrees north (WGS84)")
    lon: float = Field(description="Longitude, degrees east (WGS84)")


class GeofenceModel(Model):
    polygon: list[GeoPointModel] = Field(
        description='Vertices in order, each {"lat": .., "lon": ..}; the polygon closes itself (repeating the first vertex at the end is allowed). At least 3 distinct vertices, at most 1000, no crossing edges, within 100 km of its centre.'
    )
    max_altitude_m: float | None = Field(
        default=None, description="Ceiling inside the fence, metres above home; null for none"
    )


class GotoCheck(Model):
    """A go-to to check: the `goto` command's fields."""

    lat: float
    lon: float
    altitude: float = Field(description="Metres above home")


class GotoCheckResponse(Model):
    ok: bool = Field(description="True when the go-to breaks no rule")
    violations: list[ViolationModel]
    distance_m: float | None = Field(
        description="Horizontal distance from the vehicle to the target; null when the vehicle's position is not known"
    )


class GotoCommand(Model):
    name: Literal["goto"] = Field(default="goto")
    lat: float
    lon: float
    altitude: float = Field(description="Metres above home.")


class GroupCommandRequest(Model):
    vehicle_ids: list[str] | None = Field(
        default=None, description="The selection; every connected vehicle when unset"
    )
    command: Command


class GroupCommandResponse(Model):
    command: (
        ArmCommand
        | DisarmCommand
        | TakeoffCommand
        | LandCommand
        | ReturnToLaunchCommand
        | SetModeCommand
        | GotoCommand
        | HoldCommand
        | ChangeSpeedCommand
        | SetHomeCommand
        | RebootCommand
        | ParamListCommand
        | ParamGetCommand
        | ParamSetCommand
        | MissionUploadCommand
        | MissionDownloadCommand
        | MissionClearCommand
        | MissionSetCurrentCommand
        | ManualStartCommand
        | ManualStopCommand
    )
    results: list[VehicleCommandResult]


class HandoverOffer(Model):
    lost: list[str]
    reason: str
    missions: dict[str, list[MissionItem]]
    lanes: dict[str, list[LaneRecord]]
    lanes_moved: int
    total_s: dict[str, float] = Field(description="each drone's estimated time to finish")


class Health(Model):
    status: str = Field(description="ok, or degraded while the database is unreachable")
    database_available: bool
    vehicles: int
    connected: int
    telemetry_backlog: int
    telemetry_written: int
    write_retries: int
    rows_spooled: int = Field(
        default=0, description="audit and command-log rows waiting for the database"
    )
    rows_lost: int = Field(
        default=0,
        description="audit and command-log rows dropped since the hub started: the database, the spool file's disk and the memory held for them were all full",
    )


class HoldCommand(Model):
    """Stop and hold position (the vehicle type's loiter/hold mode), never blocked."""

    name: Literal["hold"] = Field(default="hold")


class Identity(Model):
    username: str
    role: str
    permissions: list[str]
    expires_at: float | None = Field(
        default=None, description="When the token (or session) used ends; null: never"
    )


class IssuedAgentToken(Model):
    id: int
    vehicle_id: str
    created_at: float
    created_by: str
    revoked: bool
    token: str = Field(description="Give it to the vehicle's agent (GCS_AGENT_TOKEN); shown once")


class IssuedApiToken(Model):
    id: int
    name: str
    scopes: list[str]
    created_at: float
    expires_at: float | None
    revoked: bool
    token: str = Field(description="Shown once; store it now")


class LandCommand(Model):
    name: Literal["land"] = Field(default="land")


class LaneRecord(Model):
    start: tuple[float, float] = Field(description="[lat, lon] where photos start")
    end: tuple[float, float] = Field(description="[lat, lon] where they end")
    entry: int = Field(description="the item number of the lane's entry waypoint")
    exit: int = Field(description="the item number of its exit waypoint")
    done: bool = Field(default=False)


class LeaseRefusal(Model):
    """A `control` request refused, to the client that sent it: the reason in words (the
    autopilot's setup, another pilot, the vehicle offline, ...), and where the vehicle's
    setup is the reason, the parameter change that would lift it. Every dashboard also
    sees the refusal in its event feed (a hub event of kind "control")."""

    type: Literal["lease_refused"] = Field(default="lease_refused")
    vehicle_id: str
    action: Literal["acquire", "release", "revoke"]
    reason: str
    fix: ParamFix | None = Field(default=None)


class LeaseState(Model):
    """Who flies a vehicle by hand now (holder None: nobody), sent to every client when
    it changes, and for every vehicle with a lease history when a client connects. A
    lease ends when released, revoked by an admin, expired (no input for 2 s), on the
    vehicle (the agent's deadman, frozen input, its hold button, a mode change from the
    RC transmitter or another GCS), or with a hub restart; `reason` says which."""

    type: Literal["lease"] = Field(default="lease")
    vehicle_id: str
    holder: str | None = Field(default=None)
    reason: str = Field(default="")
    resume_mode: str | None = Field(
        default=None,
        description="a mission was in progress when the lease began and is paused: set this mode to resume it (ArduPilot AUTO, PX4 MISSION)",
    )


class LiveEvent(Model):
    """An event as the live feed carries it: the agent's (a STATUSTEXT, a mode change, a
    failsafe, ...) or the hub's own (a link up or down, a command's result)."""

    vehicle_id: str
    time: float = Field(description="Unix time, seconds.")
    kind: str = Field(
        description="an agent's event kind, or one of the hub's: command, data_lost, ..."
    )
    severity: int | None = Field(default=None, description="MAV_SEVERITY: 0 emergency .. 7 debug")
    text: str
    mission_item: int | None = Field(default=None)
    photo: Photo | None = Field(default=None, description="for a 'camera' event: the photo")
    repeat: int = Field(
        default=1,
        description="how many identical events (same vehicle, kind, severity and text) this one stands for: repeats within one batch are sent once; time is the newest",
    )


class LoginRequest(Model):
    username: str
    password: str


class ManualAxes(Model):
    x: int = Field(description="pitch: forward positive, -1000..1000")
    y: int = Field(description="roll: right positive, -1000..1000")
    z: int = Field(default=500, description="throttle or climb: 0..1000, 500 mid")
    r: int = Field(default=0, description="yaw: clockwise positive, -1000..1000")
    buttons: int = Field(default=0, description="MANUAL_CONTROL buttons")


class ManualCamera(Model):
    """QGroundControl's "Manual (no camera specs)": no sensor figures, the lanes' spacing and
    the distance between photos given directly (its AdjustedFootprintSide and
    AdjustedFootprintFrontal), flown at altitude_m (a GSD cannot be computed)."""

    lane_spacing_m: float = Field(description="Distance between lanes")
    trigger_distance_m: float = Field(description="Distance between photos")
    distance_trigger: bool = Field(default=True)


class ManualEcho(Model):
    """To the lease holder: its frame ``seq`` went out to the flight controller. Its
    ``sent_ms`` against the client's clock now is the input-to-vehicle round trip."""

    type: Literal["manual_echo"] = Field(default="manual_echo")
    vehicle_id: str
    seq: int
    sent_ms: float | None = Field(default=None)


class ManualInput(Model):
    """One frame of stick input, sent by the lease holder at 25 Hz or more. Frames from
    a client without the lease, with a seq not newer than the last, or faster than
    100 Hz are refused and never forwarded; the newest frame wins."""

    type: Literal["manual"] = Field(default="manual")
    vehicle_id: str
    seq: int
    axes: ManualAxes
    source: Literal["gamepad", "touch", "keyboard", "program"] = Field(
        default="program",
        description="gamepad and program streams that repeat the same off-centre values for 3 s count as frozen and hold the vehicle; touch and keyboard do not",
    )
    sent_ms: float | None = Field(
        default=None,
        description="the client's own clock when it read the input (ms); the agent echoes it (manual_echo) so the pilot sees the input-to-vehicle round trip",
    )


class ManualStartCommand(Model):
    """Open browser control on the vehicle (the hub sends it when it grants a lease): the
    agent checks that the autopilot will take MANUAL_CONTROL from it (ArduPilot
    MAV_GCS_SYSID/SYSID_MYGCS and RC_OVERRIDE_TIME, PX4 COM_RC_IN_MODE) and switches to
    the pilot mode, which pauses a mission in progress. Refused with the reason
    otherwise. Not for the REST endpoint: a lease comes from the control message."""

    name: Literal["manual_start"] = Field(default="manual_start")


class ManualStopCommand(Model):
    """Close browser control (the lease was released): the vehicle holds."""

    name: Literal["manual_stop"] = Field(default="manual_stop")


class MapSubscriptions(Model):
    """The map layers this feed now receives (the answer to a (un)subscribe)."""

    type: Literal["map_subscriptions"] = Field(default="map_subscriptions")
    layers: list[Literal["points", "obstacles"]]


class Metrics(Model):
    telemetry_written: int
    events_written: int
    batches: int
    write_retries: int
    database_available: bool
    writer_backlog: int
    writer_capacity: int
    last_batch_s: float
    connected_agents: int


class Mission(Model):
    """One mission, the same body for the check, the upload and the download."""

    items: list[MissionItem] = Field(
        description="Flown in order from the vehicle's position; item 1 is the first (home, item 0, is the vehicle's own and is not sent)"
    )


class MissionCheckResponse(Model):
    ok: bool = Field(description="True when no rule is violated")
    violations: list[ViolationModel]
    estimate: BatteryEstimateModel | None = Field(
        description="Null when the vehicle's position, home or altitude is not known"
    )


class MissionClearCommand(Model):
    name: Literal["mission_clear"] = Field(default="mission_clear")


class MissionDownloadCommand(Model):
    name: Literal["mission_download"] = Field(default="mission_download")


class MissionItem(Model):
    """One mission item, as MISSION_ITEM_INT carries it (positions in degrees)."""

    command: int = Field(description="MAV_CMD number, e.g. 16 NAV_WAYPOINT")
    frame: int = Field(
        default=3,
        description="MAV_FRAME: 0 above sea level, 3 above home, 10 above terrain. The _INT forms 5, 6 and 11 are accepted and become 0, 3 and 10, in uploads and downloads alike. A command without a position ignores its frame (ArduPilot gives back 0).",
    )
    param1: float | None = Field(
        default=0.0,
        description="null for unset (NaN in MAVLink), where the command's spec allows NaN or calls the parameter empty (e.g. a waypoint's param4 yaw: keep the heading mode)",
    )
    param2: float | None = Field(
        default=0.0,
        description="null for unset (NaN in MAVLink), where the command's spec allows NaN or calls the parameter empty (e.g. a waypoint's param4 yaw: keep the heading mode)",
    )
    param3: float | None = Field(
        default=0.0,
        description="null for unset (NaN in MAVLink), where the command's spec allows NaN or calls the parameter empty (e.g. a waypoint's param4 yaw: keep the heading mode)",
    )
    param4: float | None = Field(
        default=0.0,
        description="null for unset (NaN in MAVLink), where the command's spec allows NaN or calls the parameter empty (e.g. a waypoint's param4 yaw: keep the heading mode)",
    )
    lat: float = Field(default=0.0)
    lon: float = Field(default=0.0)
    alt: float = Field(default=0.0, description="metres (a float32)")
    autocontinue: bool = Field(default=True)


class MissionResult(Model):
    vehicle_id: str
    outcome: CommandOutcome
    items: list[MissionItem] | None = Field(default=None)


class MissionSetCurrentCommand(Model):
    name: Literal["mission_set_current"] = Field(default="mission_set_current")
    seq: int = Field(description="1 is the first item after home")


class MissionUploadCommand(Model):
    """Replace the vehicle's mission (item 0, home, is added by the agent)."""

    name: Literal["mission_upload"] = Field(default="mission_upload")
    items: list[MissionItem]


class MosaicDetail(Model):
    survey_id: str
    processed: int = Field(default=0)
    failed: int = Field(default=0)
    pending: int = Field(default=0, description="photos queued for this survey, not yet done")
    by_vehicle: dict[str, VehicleCounts] | None = Field(default=None)
    failures: list[PhotoFailure] | None = Field(default=None, description="the latest 200 failures")
    coverage_pct: float | None = Field(
        default=None, description="percent of the survey's area under a photo; None: no area"
    )
    outline: dict[str, Any] | None = Field(
        default=None, description="GeoJSON (lon, lat) of the covered ground"
    )
    revision: int = Field(default=0, description="photos applied to the tiles so far")
    min_zoom: int | None = Field(default=None)
    max_zoom: int | None = Field(default=None)
    bounds: tuple[float, float, float, float] | None = Field(
        default=None, description="west, south, east, north of the covered ground"
    )
    tile_url: str = Field(description="the tile URL template ({z}/{x}/{y}) of this mosaic")


class Obstacle(Model):
    """A cluster of the point map, above the ground: its extent in site east/north/up
    metres; it keeps its id while it is seen."""

    id: int
    east_min: float
    east_max: float
    north_min: float
    north_max: float
    up_min: float
    up_max: float
    voxels: int
    outline: list[tuple[float, float]] = Field(
        description="the extent's corners as latitude, longitude (degrees)"
    )


class ObstaclesUpdate(Model):
    type: Literal["obstacles"] = Field(default="obstacles")
    site: SiteOrigin | None
    obstacles: list[Obstacle]


OffsetFrame = Literal["heading", "ne"]


class OffsetModel(Model):
    x: float = Field(description="Metres forward (heading) or north (ne)")
    y: float = Field(description="Metres right (heading) or east (ne)")
    up: float = Field(default=0.0, description="Metres above the leader")
    frame: OffsetFrame = Field(default="heading")


class ParamEnumValue(Model):
    value: float
    description: str


class ParamFix(Model):
    """The parameter change that would let a refused request through, as the refusal's
    words say it: for a client to offer to whoever may make it (an admin, where the
    parameter is safety-critical), never to apply by itself."""

    param: str = Field(description="e.g. WPNAV_SPEED")
    value: float


class ParamGetCommand(Model):
    name: Literal["param_get"] = Field(default="param_get")
    param: str = Field(description="e.g. WPNAV_SPEED")


class ParamListCommand(Model):
    """Read every parameter (the flight controller's whole table)."""

    name: Literal["param_list"] = Field(default="param_list")


class ParamMeta(Model):
    """What a parameter means, from the autopilot's own metadata (PX4's, over its component
    metadata protocol) or the hub's file for the firmware (ArduPilot's apm.pdef.json): its
    range, the values it takes, its units and description. A write outside the range or
    the values is refused."""

    source: Literal["autopilot", "file"] = Field(
        default="autopilot",
        description="where it came from: the autopilot's own metadata (PX4), or the hub's metadata file for the firmware family (ArduPilot's apm.pdef.json)",
    )
    description: str = Field(default="")
    units: str | None = Field(default=None)
    min: float | None = Field(default=None)
    max: float | None = Field(default=None)
    values: list[ParamEnumValue] | None = Field(default=None, description="the values it takes")
    reboot_required: bool = Field(default=False)


class ParamSetCommand(Model):
    """Set one parameter; accepted only when the flight controller echoes the new value."""

    name: Literal["param_set"] = Field(default="param_set")
    param: str = Field(description="e.g. WPNAV_SPEED")
    value: float = Field(description="PARAM_SET.param_value is a float32")


class ParamUpdate(Model):
    value: float


class ParamValues(Model):
    vehicle_id: str
    values: dict[str, float]
    metadata: ParamMeta | None = Field(
        default=None,
        description="For one parameter read or written: what it means, from the autopilot's own metadata (PX4 publishes it; the agent reads it over MAVLink FTP). Absent when the autopilot publishes none (ArduPilot) or it has not been read yet.",
    )
    range_checked: bool | None = Field(
        default=None,
        description="For a write: true if the value was checked against the metadata's range and values before it was sent (a value outside them is a 409 naming them); false if there was no metadata to check it against, so only the vehicle's own answer counted.",
    )


class Photo(Model):
    """Where and when a photo was taken, as the autopilot reports it (ArduPilot's
    CAMERA_FEEDBACK; PX4's CAMERA_TRIGGER, posed from the streams at its arrival)."""

    index: int = Field(description="the camera's image number (img_idx)")
    lat: float
    lon: float
    alt_rel: float = Field(description="metres above home")


class PhotoFailure(Model):
    photo_id: str
    vehicle_id: str
    reason: str


class Ping(Model):
    type: Literal["ping"] = Field(default="ping")
    nonce: str | None = Field(default=None)


class PointMapUpdate(Model):
    type: Literal["point_map"] = Field(default="point_map")
    map: PointMapView


class PointMapView(Model):
    site: SiteOrigin | None
    voxel_m: float
    voxels: int = Field(description="voxels in the map (``points`` may hold fewer)")
    evicted: int = Field(description="voxels dropped so far to keep the map in its bound")
    points: list[tuple[float, float, float]] = Field(
        description="voxel centres, east/north/up metres from the site origin, newest first"
    )


class Pong(Model):
    type: Literal["pong"] = Field(default="pong")
    nonce: str | None = Field(default=None)


class RebootCommand(Model):
    """Reboot the flight controller (autopilots refuse this while armed)."""

    name: Literal["reboot"] = Field(default="reboot")


class ReturnToLaunchCommand(Model):
    name: Literal["rtl"] = Field(default="rtl")


Role = Literal["viewer", "operator", "admin"]


class RoutePoint(Model):
    lat: float
    lon: float
    alt_m: float = Field(description="The leader's altitude above home")


class SafetyRailsModel(Model):
    """Site-wide rails, or one vehicle's overrides (null fields fall back to the site's)."""

    geofence: GeofenceModel | None = Field(default=None, description="Null for no geofence")
    max_distance_from_home_m: float | None = Field(
        default=None, description="Horizontal range limit, metres"
    )
    min_altitude_m: float | None = Field(
        default=None, description="Floor for targets, metres above home"
    )
    max_altitude_m: float | None = Field(default=None, description="Ceiling, metres above home")
    min_launch_battery_pct: float | None = Field(
        default=None, description="Battery needed to arm or take off, percent"
    )
    battery_reserve_pct: float = Field(
        default=20.0,
        description="Battery that must remain after a planned mission and its return home",
    )
    min_height_above_home_m: float | None = Field(
        default=2.0,
        description="Lowest a mission's navigation items (but its landings) may go, metres above home; an item above terrain counts its height above terrain as above home. Null: no such rule (a site's rails only; a vehicle's null keeps the site's)",
    )


class Sample(Model):
    """One stored telemetry sample, as charts, replays and history read it."""

    time: float = Field(description="Unix seconds")
    mode: str
    armed: bool
    lat: float | None
    lon: float | None
    alt_msl: float | None
    alt_rel: float | None
    heading_deg: float | None
    groundspeed: float | None
    climb_rate: float | None
    battery_voltage: float | None
    battery_remaining: float | None
    gps_fix: int
    satellites: int | None


class ScanDiagnosticsBody(Model):
    vehicle_id: str
    received: int
    live: int
    replayed: int
    stored: int
    cleaned_ranges: int = Field(description="ranges beyond the sensor's maximum, dropped")
    rejected: dict[str, int] = Field(description="refused scans by reason")
    source: str | None = Field(
        default=None, description="the agent's scan source: its LIDAR model, mavlink or ros2"
    )
    source_counts: dict[str, int] | None = Field(
        default=None,
        description="the agent's parser, since the agent started: packets, points, and what it dropped by reason (dropped_bad_checksum, dropped_noise_bytes, ...)",
    )


class ScanPage(Model):
    vehicle_id: str
    start: float
    end: float
    limit: int
    site: SiteOrigin | None = Field(description="the origin of the points' east/north/up")
    scans: list[ScanPoints]
    truncated: bool


class ScanPoints(Model):
    """One scan's returns in the world."""

    vehicle_id: str
    seq: int
    time: float = Field(description="UTC of the first beam, Unix seconds")
    duration_s: float
    beams: int
    replayed: bool
    enu: list[tuple[float, float, float]] = Field(
        description="east, north, up metres from the site origin, one per return"
    )
    geodetic: list[tuple[float, float, float]] = Field(
        description="latitude, longitude (degrees), altitude (m) of the same points"
    )


class ScanSubscriptions(Model):
    """The vehicles whose scans this feed now receives (the answer to a (un)subscribe)."""

    type: Literal["scan_subscriptions"] = Field(default="scan_subscriptions")
    vehicles: list[str]


class Series(Model):
    start: float
    end: float
    points: int
    metric: str
    series: dict[str, list[Sample]]


class SetHomeCommand(Model):
    """Set home (the RTL destination) to the vehicle's position, or to a given point."""

    name: Literal["set_home"] = Field(default="set_home")
    use_current: bool = Field(default=True)
    lat: float | None = Field(default=None)
    lon: float | None = Field(default=None)
    alt_msl: float | None = Field(default=None, description="metres AMSL")


class SetModeCommand(Model):
    name: Literal["set_mode"] = Field(default="set_mode")
    mode: str = Field(description="A mode name the vehicle lists.")


Shape = Literal["line", "wedge", "triangle", "column", "circle"]


class ShapeChange(Model):
    """A new shape or spacing in flight: the followers glide to their new slots."""

    shape: Shape | None = Field(default=None)
    spacing_m: float | None = Field(default=None)


class SiteOrigin(Model):
    """The origin of the site's east/north/up metres (the scans' and the point map's)."""

    lat: float
    lon: float
    alt_msl: float


class StoredFormationModel(Model):
    id: str
    started: float = Field(description="Unix time")
    started_by: str
    leader_id: str | None
    request: dict[str, Any] = Field(
        description="The formation as started (its shape and spacing as last changed)"
    )
    stopped: float | None
    stopped_by: str | None = Field(description="Null when the formation ended otherwise")
    stop_reason: str | None
    tracking: dict[str, Any] | None = Field(
        description="Per follower: RMS and maximum errors per leg and over the mission, as they stood when it stopped"
    )


class StoredFormations(Model):
    formations: list[StoredFormationModel]


class SubscribeMap(Model):
    """Send me the site's map as it changes: ``points`` (the voxel point map, its newest
    voxels, at most every few seconds) and ``obstacles`` (the clusters found in it, when
    the set changes). The current state comes at once; a slow reader gets the newest."""

    type: Literal["subscribe_map"] = Field(default="subscribe_map")
    layers: list[Literal["points", "obstacles"]]


class SubscribeScans(Model):
    """Send me this vehicle's scans (binary frames, protocol/scans.py), newest only."""

    type: Literal["subscribe_scans"] = Field(default="subscribe_scans")
    vehicle_id: str


class SurveyDetail(Model):
    progress: SurveyUpdate
    survey: SurveyRun = Field(
        description="The plan, each drone's mission and lanes (flown or not), its photos ([lat, lon] from CAMERA_FEEDBACK) and any hand-over on offer"
    )


class SurveyDroneProgress(Model):
    vehicle_id: str
    state: str = Field(description="assigned, flying, done or dropped")
    lanes_done: int
    lanes_total: int
    photos: int
    reason: str | None = Field(default=None, description="why it dropped out")


class SurveyFile(Model):
    format: Literal["plan", "kml", "geojson"] = Field(
        description="plan: a QGroundControl .plan with a Survey item (its polygon, camera, altitude or GSD, overlaps, angle, turnaround); kml: the first Polygon of a KML file (Google Earth); geojson: a Polygon, Feature or FeatureCollection"
    )
    content: str = Field(description="the file's text")


class SurveyList(Model):
    surveys: list[SurveyUpdate]


class SurveyPart(Model):
    vehicle_id: str
    mission: Mission
    lanes: int
    photo_count: int
    path_length_m: float
    transit_s: float
    survey_s: float
    home_s: float
    total_s: float = Field(description="Transit to the part, the part, and the way home")
    lane_paths: list[list[list[float]]] = Field(
        description="Each lane's [[lat, lon], [lat, lon]] from start to end, for the map"
    )
    check: MissionCheckResponse


class SurveyPhotos(Model):
    survey_id: str
    drones: list[DronePhotos]
    photos: list[dict[str, Any]] = Field(description="each stored photo: id, vehicle, pose")


class SurveyPreview(Model):
    ok: bool = Field(
        description="True when every part's mission passes the safety rails and each drone carries the camera the plan assumes (rule survey_camera)"
    )
    altitude_m: float
    gsd_cm: float | None = Field(description="null for a manual camera (no sensor figures)")
    footprint_side_m: float
    footprint_frontal_m: float
    lane_spacing_m: float
    trigger_distance_m: float
    angle_deg: float
    area_m2: float
    coverage_pct: float = Field(description="Area (holes excluded) seen by the photos' footprints")
    coverage_at_overlaps_pct: float = Field(
        description="Area seen with at least the requested side and front overlaps"
    )
    photo_count: int
    lanes: int
    parts: list[SurveyPart]


class SurveyRequest(Model):
    area: GeoJsonPolygon
    camera: str | CameraModel | ManualCamera = Field(
        description="A preset's name (e.g. sony_a6000_16mm), the camera's figures, or a manual camera (lane spacing and trigger distance, with altitude_m)"
    )
    altitude_m: float | None = Field(default=None, description="Above home; or give gsd_cm")
    gsd_cm: float | None = Field(default=None, description="cm per pixel; or give altitude_m")
    side_overlap_pct: float = Field(default=70.0)
    front_overlap_pct: float = Field(default=80.0)
    angle_deg: float | None = Field(
        default=None, description="Lane heading; null chooses the fastest"
    )
    speed_ms: float = Field(default=10.0)
    turnaround_m: float = Field(default=10.0)
    hover_and_capture: bool = Field(default=False)
    vehicle_ids: list[str]


class SurveyRun(Model):
    id: str
    created: float
    started: float | None = Field(default=None)
    state: SurveyState = Field(default="planned")
    request: SurveyRequest
    altitude_m: float
    footprint_side_m: float
    footprint_frontal_m: float
    lane_spacing_m: float
    trigger_distance_m: float
    angle_deg: float
    drones: list[DroneRun]
    offer: HandoverOffer | None = Field(default=None)
    handovers: int = Field(default=0)
    note: str = Field(default="")


SurveyState = Literal["planned", "flying", "handover_offered", "done", "aborted", "failed"]


class SurveyUpdate(Model):
    """An area survey's progress, at most one a second per survey (newest wins): lanes
    flown, photos triggered (CAMERA_FEEDBACK) and the share of the area their footprints
    cover, overall and per drone, and whether a hand-over awaits the operator."""

    type: Literal["survey"] = Field(default="survey")
    survey_id: str
    state: str = Field(description="planned, flying, handover_offered, done, aborted, failed")
    lanes_done: int
    lanes_total: int
    photos: int
    covered_pct: float
    drones: list[SurveyDroneProgress]
    handover_lanes: int | None = Field(
        default=None, description="lanes a hand-over offers to move; null if none offered"
    )


class TakeoffCommand(Model):
    """Guided take-off: switches to the guided mode and arms first if needed, as QGC does."""

    name: Literal["takeoff"] = Field(default="takeoff")
    altitude: float = Field(description="Metres above home.")


class TelemetryPage(Model):
    vehicle_id: str
    start: float
    end: float
    limit: int
    samples: list[TelemetrySample]
    truncated: bool = Field(description="True when more samples exist in the range")


class TelemetrySample(Model):
    time: float = Field(description="Unix seconds")
    mode: str
    armed: bool
    lat: float | None
    lon: float | None
    alt_msl: float | None
    alt_rel: float | None
    heading_deg: float | None
    groundspeed: float | None
    climb_rate: float | None
    battery_voltage: float | None
    battery_remaining: float | None
    gps_fix: int
    satellites: int | None
    seq: int


class TileSet(Model):
    name: str = Field(description="the file name without .mbtiles or .pmtiles")
    kind: str = Field(description="mbtiles or pmtiles")
    media_type: str
    min_zoom: int
    max_zoom: int
    bounds: tuple[float, float, float, float] | None = Field(
        description="west, south, east, north in degrees, when the file says"
    )
    attribution: str
    url: str = Field(description="the tile URL template, with the set's version")


class Tlog(Model):
    id: int
    vehicle_id: str
    filename: str
    size: int
    uploaded_at: float


class TrackingModel(Model):
    live_xy_m: float | None = Field(description="The newest horizontal error from its slot")
    live_z_m: float | None = Field(description="The newest vertical error")
    legs: dict[str, ErrorStatsModel] = Field(
        description="Per leg of the route (numbered from 1), while the leader flies it"
    )
    mission: ErrorStatsModel = Field(description="Over every leg so far")


class Unprocessable(Model):
    """A value the route cannot take (``detail`` lists each problem, naming its field and
    rule), or a command or mission the safety rails refuse (``detail`` says so in one
    sentence and ``violations`` lists every violated rule)."""

    detail: str | list[ValidationProblem]
    violations: list[dict[str, Any]] | None = Field(default=None)


class UnsubscribeMap(Model):
    type: Literal["unsubscribe_map"] = Field(default="unsubscribe_map")
    layers: list[Literal["points", "obstacles"]]


class UnsubscribeScans(Model):
    type: Literal["unsubscribe_scans"] = Field(default="unsubscribe_scans")
    vehicle_id: str


class UploadStatus(Model):
    received: int = Field(description="bytes the hub has committed; the next chunk's offset")
    size: int | None = Field(default=None, description="the photo's size, once declared")
    state: str = Field(description="receiving, stored or refused")
    reason: str | None = Field(default=None, description="why it was refused")


class User(Model):
    username: str
    role: str
    disabled: bool
    created_at: float


class UserCreate(Model):
    username: str
    password: str = Field(description="at least 12 characters, and not a common or guessable one")
    role: Role


class UserUpdate(Model):
    role: Role | None = Field(default=None)
    disabled: bool | None = Field(default=None)
    password: str | None = Field(default=None)


class ValidationProblem(Model):
    loc: list[str | int] = Field(description="Where: body, query or path, then the field")
    msg: str = Field(description="The rule the value broke")
    type: str


class VehicleBatch(Model):
    """The vehicles that changed since this connection's last batch, each once (its newest
    state): one frame per tick for the whole fleet, not one per vehicle. A vehicle's state
    goes out at most once per the hub's ``ui_update_interval_s``; a client that reads too
    slowly gets the newest state of each vehicle when it catches up, never a backlog."""

    type: Literal["vehicles"] = Field(default="vehicles")
    vehicles: list[VehicleChange]


class VehicleChange(Model):
    """One vehicle's live update. It carries ``autopilot``, ``vehicle_type`` and ``modes``
    (a third of the frame, ten times a second) only the first time this connection shows
    the vehicle and when they change (its agent reconnected with another hello, or sent
    the autopilot's own mode list); the fleet
    snapshot a new connection starts with always has them."""

    id: str
    autopilot: str | None = Field(
        default=None,
        description="Left out when this feed has already sent it and it has not changed since: keep the value from the fleet snapshot or an earlier update.",
    )
    vehicle_type: str | None = Field(
        default=None,
        description="Left out when this feed has already sent it and it has not changed since: keep the value from the fleet snapshot or an earlier update.",
    )
    modes: list[str] | None = Field(
        default=None,
        description="Left out when this feed has already sent it and it has not changed since: keep the value from the fleet snapshot or an earlier update.",
    )
    connected: bool
    last_seen: float | None = Field(default=None, description="Unix time of the last telemetry.")
    airborne_since: float | None = Field(
        default=None,
        description="Unix time (the vehicle's telemetry clock) of its take-off: the first sample in which it flew (armed, landed_state takeoff/in_air/landing) after one in which it was on the ground. Null while it is on the ground, and while the hub has not seen it take off (it was already flying when the hub first heard from it): unknown, never zero.",
    )
    state: VehicleState | None = Field(default=None)


class VehicleCommandResult(Model):
    vehicle_id: str
    status_code: int = Field(description="What a single-vehicle call would have returned")
    outcome: CommandOutcome | None = Field(default=None)
    error: str | None = Field(default=None)
    violations: list[dict[str, Any]] | None = Field(default=None)


class VehicleCounts(Model):
    processed: int = Field(default=0)
    failed: int = Field(default=0)


class VehiclePhotos(Model):
    vehicle_id: str
    received: int = Field(description="photos stored")
    failed: int = Field(description="photos refused")
    reasons: dict[str, int] = Field(description="refusals by reason code")
    photos: list[dict[str, Any]] = Field(
        description="its newest photos, stored and refused: id, state, reason, pose"
    )


class VehicleState(Model):
    """One telemetry snapshot, assembled by the agent from the latest MAVLink messages.
    The hub refuses a snapshot holding a physically impossible value (STATE_BOUNDS:
    latitude beyond ±90, an altitude of 1e308 ...): not stored, not shown, counted."""

    fcu_connected: bool = Field(default=True)
    mode: str = Field(default="UNKNOWN")
    armed: bool = Field(default=False)
    system_status: str = Field(default="UNKNOWN")
    landed_state: Literal["on_ground", "takeoff", "in_air", "landing"] | None = Field(
        default=None,
        description="Whether it flies: on_ground, or airborne (takeoff, in_air, landing). Use this, not the altitude (a field above or below home misleads it). Null until known.",
    )
    landed_state_source: Literal["autopilot", "derived"] | None = Field(
        default=None,
        description="autopilot: EXTENDED_SYS_STATE.landed_state (ArduCopter, ArduPlane, PX4); derived: the agent's guess from armed, the altitude above home and the climb rate, where the autopilot does not say (ArduPilot Rover, old firmware): never takeoff or landing, and a ground vehicle is always on_ground",
    )
    lat: float | None = Field(default=None)
    lon: float | None = Field(default=None)
    alt_msl: float | None = Field(default=None, description="Metres above mean sea level.")
    alt_rel: float | None = Field(default=None, description="Metres above home.")
    heading_deg: float | None = Field(default=None)
    groundspeed: float | None = Field(default=None, description="m/s")
    climb_rate: float | None = Field(default=None, description="m/s, up is positive")
    vn: float | None = Field(default=None, description="m/s north (GLOBAL_POSITION_INT.vx)")
    ve: float | None = Field(default=None, description="m/s east (GLOBAL_POSITION_INT.vy)")
    roll_deg: float | None = Field(default=None)
    pitch_deg: float | None = Field(default=None)
    battery_voltage: float | None = Field(default=None)
    battery_current: float | None = Field(default=None, description="A")
    battery_remaining: float | None = Field(default=None, description="percent")
    gps_fix: int = Field(default=0, description="GPS_FIX_TYPE: 0-1 none, 2 2D, 3 3D, 4+ DGPS/RTK")
    satellites: int | None = Field(default=None)
    ready_to_fly: bool | None = Field(
        default=None,
        description="the autopilot's pre-arm checks and estimator allow a take-off (EKF_STATUS_REPORT, SYS_STATUS, PreArm texts); null until it has said",
    )
    not_ready_reason: str | None = Field(
        default=None, description="why it is not ready, when it is not"
    )
    home_lat: float | None = Field(default=None)
    home_lon: float | None = Field(default=None)
    home_alt_msl: float | None = Field(default=None)
    mission_current: int | None = Field(
        default=None, description="the mission item being flown (MISSION_CURRENT)"
    )
    mission_total: int | None = Field(default=None)
    position_source: str | None = Field(
        default=None, description="the position source in use, e.g. GPS_RAW_INT or GPS2_RAW (RTK)"
    )
    fcu_receive_errors: int = Field(
        default=0, description="garbage bytes and bad frames skipped on the FCU link"
    )
    outbox_pending: int = Field(default=0, description="frames not yet stored by the hub")
    outbox_dropped: int = Field(
        default=0, description="frames the agent dropped because its outbox was full"
    )


class VehicleSummary(Model):
    id: str
    autopilot: str
    vehicle_type: str
    modes: list[str]
    connected: bool
    last_seen: float | None = Field(default=None, description="Unix time of the last telemetry.")
    airborne_since: float | None = Field(
        default=None,
        description="Unix time (the vehicle's telemetry clock) of its take-off: the first sample in which it flew (armed, landed_state takeoff/in_air/landing) after one in which it was on the ground. Null while it is on the ground, and while the hub has not seen it take off (it was already flying when the hub first heard from it): unknown, never zero.",
    )
    state: VehicleState | None = Field(default=None)


class ViewerLooksAt(Model):
    vehicle_id: str
    look_at: tuple[float, float, float] = Field(description="East, north, up in the view, m")


class ViewerSelection(Model):
    secret: str = Field(description="What the viewer's page said")
    vehicle_id: str


class ViolationModel(Model):
    rule: Literal[
        "geofence",
        "geofence_max_altitude",
        "max_altitude",
        "min_altitude",
        "min_height_above_home",
        "max_distance_from_home",
        "min_launch_battery",
        "battery_sufficiency",
        "home_altitude",
        "position_unknown",
        "mission_item",
        "mission_unchecked",
        "survey_camera",
    ] = Field(description="Stable name of the rule that was broken")
    message: str = Field(description="What is wrong, with the numbers and units")
    limit: float | None = Field(default=None, description="The rule's limit, where it has one")
    value: float | None = Field(default=None, description="The offending value, where it has one")
    items: list[int] | None = Field(
        default=None,
        description="The mission items at fault (1 is the first after home; a leg is listed by the item it flies to); empty for a rule about the vehicle or a command",
    )


# What the hub sends on the live feed.
FeedMessage = Annotated[
    FleetSnapshot
    | VehicleBatch
    | EventBatch
    | ScanSubscriptions
    | Pong
    | ErrorReply
    | LeaseState
    | LeaseRefusal
    | SurveyUpdate
    | ManualEcho
    | MapSubscriptions
    | PointMapUpdate
    | ObstaclesUpdate,
    Field(discriminator="type"),
]
FEEDMESSAGE_ADAPTER: TypeAdapter[FeedMessage] = TypeAdapter(FeedMessage)


# What a client sends on the feed.
ClientMessage = Annotated[
    Ping
    | ControlRequest
    | ManualInput
    | SubscribeScans
    | UnsubscribeScans
    | SubscribeMap
    | UnsubscribeMap,
    Field(discriminator="type"),
]
CLIENTMESSAGE_ADAPTER: TypeAdapter[ClientMessage] = TypeAdapter(ClientMessage)


# One vehicle command, picked by its name.
Command = Annotated[
    ArmCommand
    | DisarmCommand
    | TakeoffCommand
    | LandCommand
    | ReturnToLaunchCommand
    | SetModeCommand
    | GotoCommand
    | HoldCommand
    | ChangeSpeedCommand
    | SetHomeCommand
    | RebootCommand
    | ParamListCommand
    | ParamGetCommand
    | ParamSetCommand
    | MissionUploadCommand
    | MissionDownloadCommand
    | MissionClearCommand
    | MissionSetCurrentCommand,
    Field(discriminator="name"),
]
COMMAND_ADAPTER: TypeAdapter[Command] = TypeAdapter(Command)


# Models that name one another are completed once every class exists.
for _model in (
    AccessToken,
    AgentToken,
    ApiToken,
    ApiTokenRequest,
    ArmCommand,
    AuditPage,
    AuditRecord,
    BatteryEstimateModel,
    Body_token_api_v1_auth_token_post,
    CameraModel,
    CameraPreset,
    ChangeSpeedCommand,
    ClientConfig,
    CommandOutcome,
    CommandPage,
    CommandRecord,
    CommandResponse,
    ControlRequest,
    CurrentItem,
    DisarmCommand,
    DronePhotos,
    DroneRun,
    ErrorMessage,
    ErrorReply,
    ErrorStatsModel,
    EventBatch,
    EventPage,
    EventRecord,
    FleetSnapshot,
    Flight,
    FlightPage,
    FlightTelemetry,
    FollowerModel,
    FormationRequest,
    FormationStatus,
    GeoJsonPolygon,
    GeoPointModel,
    GeofenceModel,
    GotoCheck,
    GotoCheckResponse,
    GotoCommand,
    GroupCommandRequest,
    GroupCommandResponse,
    HandoverOffer,
    Health,
    HoldCommand,
    Identity,
    IssuedAgentToken,
    IssuedApiToken,
    LandCommand,
    LaneRecord,
    LeaseRefusal,
    LeaseState,
    LiveEvent,
    LoginRequest,
    ManualAxes,
    ManualCamera,
    ManualEcho,
    ManualInput,
    ManualStartCommand,
    ManualStopCommand,
    MapSubscriptions,
    Metrics,
    Mission,
    MissionCheckResponse,
    MissionClearCommand,
    MissionDownloadCommand,
    MissionItem,
    MissionResult,
    MissionSetCurrentCommand,
    MissionUploadCommand,
    MosaicDetail,
    Obstacle,
    ObstaclesUpdate,
    OffsetModel,
    ParamEnumValue,
    ParamFix,
    ParamGetCommand,
    ParamListCommand,
    ParamMeta,
    ParamSetCommand,
    ParamUpdate,
    ParamValues,
    Photo,
    PhotoFailure,
    Ping,
    PointMapUpdate,
    PointMapView,
    Pong,
    RebootCommand,
    ReturnToLaunchCommand,
    RoutePoint,
    SafetyRailsModel,
    Sample,
    ScanDiagnosticsBody,
    ScanPage,
    ScanPoints,
    ScanSubscriptions,
    Series,
    SetHomeCommand,
    SetModeCommand,
    ShapeChange,
    SiteOrigin,
    StoredFormationModel,
    StoredFormations,
    SubscribeMap,
    SubscribeScans,
    SurveyDetail,
    SurveyDroneProgress,
    SurveyFile,
    SurveyList,
    SurveyPart,
    SurveyPhotos,
    SurveyPreview,
    SurveyRequest,
    SurveyRun,
    SurveyUpdate,
    TakeoffCommand,
    TelemetryPage,
    TelemetrySample,
    TileSet,
    Tlog,
    TrackingModel,
    Unprocessable,
    UnsubscribeMap,
    UnsubscribeScans,
    UploadStatus,
    User,
    UserCreate,
    UserUpdate,
    ValidationProblem,
    VehicleBatch,
    VehicleChange,
    VehicleCommandResult,
    VehicleCounts,
    VehiclePhotos,
    VehicleState,
    VehicleSummary,
    ViewerLooksAt,
    ViewerSelection,
    ViolationModel,
):
    _model.model_rebuild()
