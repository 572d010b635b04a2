"""REST request and response bodies (the WebSocket messages live in protocol.messages)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from protocol.messages import Command, CommandOutcome


class Health(BaseModel):
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
        description="audit and command-log rows dropped since the hub started: the database, "
        "the spool file's disk and the memory held for them were all full",
    )


class ClientConfig(BaseModel):
    basemap_url: str | None = Field(description="the online street map (XYZ); None: off")
    basemap_attribution: str
    basemap_max_zoom: int
    imagery_url: str | None = Field(default=None, description="online imagery (XYZ); None: off")
    imagery_attribution: str = ""
    imagery_max_zoom: int = 19
    protocol: int


class CommandResponse(BaseModel):
    vehicle_id: str
    command: Command
    outcome: CommandOutcome


class Sample(BaseModel):
    """One stored telemetry sample, as charts, replays and history read it."""

    model_config = ConfigDict(from_attributes=True)

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


class TelemetrySample(Sample):
    seq: int


class TelemetryPage(BaseModel):
    vehicle_id: str
    start: float
    end: float
    limit: int
    samples: list[TelemetrySample]
    truncated: bool = Field(description="True when more samples exist in the range")
