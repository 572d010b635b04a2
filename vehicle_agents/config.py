"""The agent's settings: CLI flags, over environment variables (GCS_AGENT_*), over a TOML
config file (``/etc/gcs/agent.toml`` or ``--config``), over defaults.

Each setting has one name in all three: the field name is the file's key, ``--`` plus the
name with dashes is the flag, and ``GCS_AGENT_`` plus the upper-case name is the variable.
"""

from __future__ import annotations

import difflib
import os
import tomllib
from pathlib import Path
from typing import Any, Literal
from urllib.parse import urlsplit, urlunsplit

from pydantic import Field, SecretStr, ValidationError, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from protocol.messages import AGENT_WS_PATH
from protocol.photos import parse_camera_model


class AgentSettings(BaseSettings):
    model_config = SettingsConfigDict(
        env_prefix="GCS_AGENT_", extra="forbid", hide_input_in_errors=True
    )

    fcu: str = Field(
        default="tcp:127.0.0.1:5760",
        description="pymavlink connection URL of the flight controller",
    )
    hub: str = Field(default="ws://127.0.0.1:8000", description="hub WebSocket URL")
    hub_fallback: list[str] = Field(
        default_factory=list,
        description="more hubs of the same deployment (several hubs), tried in turn after "
        "'hub' when a link fails; photos and .tlogs still go to 'hub'",
    )
    # Optional here so that `--print-id` runs before enrolment; `load_agent_settings`
    # requires it for a running agent, naming the three ways to give it.
    token: SecretStr | None = Field(
        default=None,
        description="this vehicle's agent token, from the hub's enrolment",
    )
    vehicle_id: str | None = Field(
        default=None,
        description="default <vehicle type>_<first 4 hex of /etc/machine-id>, the type as "
        "the flight controller's heartbeat names it (multirotor, rover, fixed_wing, ...); "
        "--print-id shows it",
    )
    telemetry_rate_hz: float = Field(
        default=10.0, gt=0, le=50, description="telemetry snapshots sent per second"
    )
    # Not 255, which is QGroundControl's, Mission Planner's and MAVProxy's default: with
    # --mavlink-forward they join the agent's MAVLink network, where a system id must name
    # one system: the vehicle addresses its answers by it, and routers (ours, mavlink-router,
    # ArduPilot's own) learn which link each id lives on. 254 is also skybrush-server's
    # default. The price: ArduPilot takes MANUAL_CONTROL/RC overrides and counts GCS-failsafe
    # heartbeats only from SYSID_MYGCS (MAV_GCS_SYSID from 4.7; default 255), so set that to
    # 254 for them to follow the agent (4.7: MAV_GCS_SYSID=254 with MAV_GCS_SYSID_HI=255
    # accepts a guest QGC as well).
    source_system: int = Field(default=254, ge=1, le=255, description="our MAVLink system id")
    tlog_dir: Path | None = Field(
        default=None, description="keep an onboard .tlog per flight here, upload after landing"
    )
    tlog_keep_days: float = Field(
        default=7.0,
        ge=0,
        description="uploaded onboard .tlogs older than this are deleted (0: right after "
        "upload); a file not yet uploaded is always kept",
    )
    tlog_keep_mb: float = Field(
        default=2048.0,
        ge=0,
        description="all onboard .tlogs together are held under this many MiB by deleting "
        "the oldest uploaded ones; a file not yet uploaded is always kept",
    )
    outbox_limit: int = Field(
        default=36000,
        ge=10,
        description="frames kept until the hub stores them (36,000 = 1 h of 10 Hz telemetry); "
        "when full, the oldest are dropped and counted",
    )
    outbox_dir: Path | None = Field(
        default=None,
        description="keep the outbox here while the hub is unreachable, so it survives "
        "outages and agent restarts; without it the outbox lives in memory only",
    )
    health_file: Path | None = Field(
        default=None,
        description="rewrite this file every 5 s with whether the flight controller and "
        "the hub are linked, for `--health` (a container's health check)",
    )
    hub_failsafe_action: Literal["continue", "hold", "rtl"] = Field(
        default="continue",
        description="what the vehicle does when the hub link has been lost for "
        "hub_failsafe_timeout_s (the flight controller's own failsafes still apply)",
    )
    hub_failsafe_timeout_s: float = Field(
        default=10.0, gt=0, le=3600, description="seconds without the hub before acting"
    )
    mavlink_forward: list[str] = Field(
        default_factory=list,
        description="MAVLink endpoints for third-party GCSs, e.g. udpout:10.0.0.5:14550 or "
        "udpin:0.0.0.0:14551",
    )
    lidar: str | None = Field(
        default=None,
        description="a 2-D LIDAR to relay: a serial LIDAR's device (/dev/ttyUSB0; see "
        "lidar_model), the "
        "simulator's tcp://HOST:PORT, 'mavlink' for the flight controller's "
        "OBSTACLE_DISTANCE (PX4) or DISTANCE_SENSOR (ArduPilot's proximity sectors), or "
        "ros2:TOPIC for a ROS 2 LaserScan topic (where rclpy is installed)",
    )
    lidar_model: str = Field(
        default="ydlidar-tmini-pro",
        description="the serial LIDAR's model, which picks its wire format and default baud "
        "rate: rplidar-a1, -a2, -a3, -c1, -s1, -s2, ydlidar-x2, -x4, -g4, -tmini-pro, ld06, "
        "ld19, stl27l (docs/reference.md, 'Sensors'; `gcs-agent lidar-probe DEVICE` finds it)",
    )
    lidar_baud: int | None = Field(
        default=None, gt=0, description="the LIDAR's serial baud rate (default: the model's)"
    )
    lidar_scan_mode: int = Field(
        default=0,
        ge=0,
        le=255,
        description="RPLIDAR only: 0 for the standard scan, N for an express scan in the "
        "sensor's working mode N (express, dense or ultra capsules, as the sensor answers)",
    )
    lidar_resolution_deg: float = Field(
        default=0.5, ge=0.1, le=10.0, description="the angle between beams of a relayed scan"
    )
    lidar_mount: str = Field(
        default="0,0,0,0,0,0",
        description="where the LIDAR sits: forward,right,down (m),roll,pitch,yaw (deg) from "
        "the vehicle's centre and axes",
    )
    scan_budget: int = Field(
        default=6000,
        ge=1,
        description="scans kept while the hub is unreachable (6,000 = 10 min at 10 Hz, "
        "about 10 MB; on disk in outbox_dir when it is set), replayed oldest first after "
        "the newest; when full, the oldest are dropped and counted",
    )
    camera: str | None = Field(
        default=None,
        description="a nadir camera whose photos the autopilot's camera trigger "
        "(CAMERA_FEEDBACK; PX4: CAMERA_TRIGGER, CAMERA_IMAGE_CAPTURED) takes: sim+http://HOST:PORT "
        "for the simulator's (gcs sim "
        "--camera), opencv:DEVICE for a USB/CSI camera (opencv:0, opencv:/dev/video2; needs "
        "OpenCV, the agent's `camera` extra), mavlink for a MAVLink camera component (each "
        "CAMERA_IMAGE_CAPTURED's http(s) file_url is fetched), folder:PATH for a camera that "
        "writes its files into PATH (an SD card, gphoto2's downloads; each new JPEG is "
        "paired with a trigger)",
    )
    camera_model: str = Field(
        default="13.2,8.8,5472,3648,8.8",
        description="the camera: sensor width,height (mm),image width,height (px),focal "
        "length (mm); the default is a DJI Phantom 4 Pro's, the survey preset "
        "dji_phantom4_pro",
    )
    photo_dir: Path | None = Field(
        default=None,
        description="where photos wait for the hub (default: photos/ in outbox_dir)",
    )
    photo_budget_mb: float = Field(
        default=4096.0,
        gt=0,
        description="the waiting photos are held under this many MiB; when over, the "
        "oldest are deleted and counted",
    )
    photo_upload_rate_mb: float = Field(
        default=2.0,
        gt=0,
        description="photo uploads use at most this many MiB/s on average, so telemetry "
        "keeps its share of the link",
    )
    photo_upload_concurrency: int = Field(
        default=1, ge=1, le=8, description="photos uploaded at once"
    )
    stream_rates_hz: dict[str, float] = Field(
        default_factory=dict,
        description="extra or changed MAVLink message rates to request, e.g. "
        "{ATTITUDE = 10} (0 stops a message); merged over the agent's defaults",
    )

    def token_value(self) -> str:
        """The token, which a running agent cannot do without."""
        if self.token is None:
            raise SettingsError("no agent token: give it as " + ways_to_give("token"))
        return self.token.get_secret_value()

    @field_validator("stream_rates_hz")
    @classmethod
    def _known_messages(cls, rates: dict[str, float]) -> dict[str, float]:
        from vehicle_agents.fcu.stream_plan import stream_plan

        stream_plan(rates)  # names MAVLink knows, rates >= 0: refused here, before flight
        return rates

    @field_validator("lidar")
    @classmethod
    def _lidar(cls, value: str | None) -> str | None:
        from vehicle_agents.sensors.ros2 import SCHEME, rclpy_available

        if value is not None and value.startswith(SCHEME) and not rclpy_available():
            raise ValueError(
                f"{value}: a ROS 2 LaserScan topic needs rclpy, which is not importable here "
                "(source the ROS 2 installation's setup script first)"
            )
        return value

    @field_validator("lidar_model")
    @classmethod
    def _lidar_model(cls, name: str) -> str:
        from vehicle_agents.sensors.lidar.models import model_named

        model_named(name)
        return name

    @field_validator("lidar_mount")
    @classmethod
    def _mount(cls, text: str) -> str:
        from vehicle_agents.sensors.relay import parse_mount

        parse_mount(text)
        return text

    @field_validator("camera_model")
    @classmethod
    def _camera_model(cls, text: str) -> str:
        parse_camera_model(text)
        return text

    @field_validator("camera")
    @classmethod
    def _camera(cls, value: str | None) -> str | None:
        if value is None:
            return value
        folder = value.startswith("folder:") and bool(value.removeprefix("folder:"))
        if not (value.startswith(("sim+http://", "opencv:")) or value == "mavlink" or folder):
            raise ValueError(
                f"{value}: a camera is sim+http://HOST:PORT (the simulator), "
                "opencv:DEVICE, mavlink (a MAVLink camera component) or folder:PATH (a "
                "folder the camera writes its files into)"
            )
        return value

    def photo_folder(self) -> Path:
        """Where photos wait: photo_dir, else photos/ in outbox_dir."""
        if self.photo_dir is not None:
            return self.photo_dir
        if self.outbox_dir is not None:
            return self.outbox_dir / "photos"
        raise SettingsError(
            "a camera needs a folder for its photos: give it as " + ways_to_give("photo_dir")
        )

    @field_validator("hub_fallback")
    @classmethod
    def _agent_endpoints(cls, urls: list[str]) -> list[str]:
        return [cls._agent_endpoint(url) for url in urls]

    @field_validator("hub")
    @classmethod
    def _agent_endpoint(cls, url: str) -> str:
        """Accept the hub's base URL as well as the full agent endpoint."""
        parts = urlsplit(url)
        if parts.scheme not in ("ws", "wss"):
            raise ValueError("hub URL must start with ws:// or wss://")
        if parts.path in ("", "/"):
            parts = parts._replace(path=AGENT_WS_PATH)
        return urlunsplit(parts)


def default_vehicle_id(model: str, machine_id_file: Path = Path("/etc/machine-id")) -> str:
    """``<model>_<first 4 hex of the machine id>``, the seed framework's naming."""
    try:
        machine_id = machine_id_file.read_text().strip()[:4]
    except OSError:
        machine_id = "0000"
    return f"{model}_{machine_id or '0000'}"


def hub_http_base(hub_ws_url: str) -> str:
    """The hub's HTTP base URL, from the agent's WebSocket URL."""
    parts = urlsplit(hub_ws_url)
    scheme = "https" if parts.scheme == "wss" else "http"
    return urlunsplit((scheme, parts.netloc, "", "", ""))


DEFAULT_CONFIG_FILE = Path("/etc/gcs/agent.toml")
ENV_PREFIX = "GCS_AGENT_"


class SettingsError(ValueError):
    """A setting is missing or unknown; the message says how to give it."""


def flag_for(name: str) -> str:
    """The command-line flag of a setting: ``telemetry_rate_hz`` -> ``--telemetry-rate-hz``."""
    return "--" + name.replace("_", "-")


def ways_to_give(name: str) -> str:
    """The three places a setting can come from, by their names."""
    return f"{flag_for(name)}, {ENV_PREFIX}{name.upper()} or `{name} = ...` in the config file"


def describe_errors(error: ValidationError) -> str:
    """One line per refused setting, naming how to give it, instead of pydantic's dump."""
    lines = []
    for problem in error.errors():
        name = str(problem["loc"][0]) if problem["loc"] else ""
        if name in AgentSettings.model_fields:
            lines.append(f"  {name}: {problem['msg']} (give it as {ways_to_give(name)})")
        else:
            lines.append(f"  {name}: {problem['msg']}")
    return "\n".join(lines)


def _unknown_key(path: Path, key: str) -> str:
    close = difflib.get_close_matches(key, AgentSettings.model_fields, n=1, cutoff=0.6)
    hint = f"did you mean {close[0]!r}?" if close else "see the table in docs/reference.md"
    return f"{path}: unknown setting {key!r}; {hint}"


def load_agent_settings(
    overrides: dict[str, Any], config_file: Path | None = None, *, require_token: bool = True
) -> AgentSettings:
    """Settings with the precedence operators expect: flags, then the environment, then
    the config file (keys as in the environment, lower-case, without the prefix).

    ValidationError for a bad value, SettingsError for an unknown key in the file or (with
    ``require_token``) no token anywhere."""
    path = config_file or (DEFAULT_CONFIG_FILE if DEFAULT_CONFIG_FILE.is_file() else None)
    from_file: dict[str, Any] = {}
    if path is not None:
        with path.open("rb") as file:
            try:
                from_file = tomllib.load(file)
            except tomllib.TOMLDecodeError as error:
                raise SettingsError(f"{path}: not valid TOML: {error}") from None
        unknown = sorted(set(from_file) - set(AgentSettings.model_fields))
        if unknown:
            raise SettingsError("; ".join(_unknown_key(path, key) for key in unknown))
    # A value from the file is passed explicitly, which would outrank the environment;
    # so it is dropped wherever the environment sets that field.
    from_file = {
        name: value
        for name, value in from_file.items()
        if f"{ENV_PREFIX}{name.upper()}" not in os.environ
    }
    given = {name: value for name, value in overrides.items() if value is not None}
    settings = AgentSettings(**{**from_file, **given})
    if settings.camera is not None:
        settings.photo_folder()  # a camera without a folder for its photos: refused now
    if require_token and settings.token is None:
        raise SettingsError(
            "no agent token: give it as " + ways_to_give("token") + " (an admin creates it "
            "with POST /api/v1/vehicles/{vehicle_id}/agent-tokens; `--print-id` shows the id)"
        )
    return settings
