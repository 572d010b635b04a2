"""The live path: agents' links and commands, telemetry's way to the store, the dashboards'
feeds and their pacing."""

from __future__ import annotations

from pydantic import BaseModel, Field

from protocol.messages import MAX_FRAME_BYTES


class LiveSettings(BaseModel):
    """Agents, commands, telemetry batching and the client feeds."""

    command_timeout_s: float = Field(default=15.0, gt=0, le=120)
    formation_join_timeout_s: float = Field(
        default=60.0,
        gt=0,
        le=3600,
        description="a formation whose followers are not all in their slots this long "
        "after its start ends, and every member holds",
    )
    fleet_speedup: float = Field(
        default=1.0,
        ge=1.0,
        le=100.0,
        description="a simulated fleet's speed-up (the simulators' --speedup, one for the "
        "fleet): formations fly their routes in the vehicles' seconds; 1 for aircraft, and "
        "only in development",
    )

    telemetry_batch_size: int = Field(default=500, ge=1)
    telemetry_flush_interval_s: float = Field(default=0.25, gt=0)
    telemetry_queue_limit: int = Field(default=20_000, ge=100)
    ui_update_interval_s: float = Field(
        default=0.1, gt=0, description="per-client pacing of live event batches"
    )
    ui_vehicle_interval_s: float = Field(
        default=0.05,
        gt=0,
        description="the least time between two updates of one vehicle to the client feeds",
    )
    ui_batch_interval_s: float = Field(
        default=0.01, gt=0, description="the least time between two vehicle batches to a feed"
    )

    slow_client_timeout_s: float = Field(
        default=10.0,
        gt=0,
        description="a client feed that takes no vehicle batch for this long is closed (4408)",
    )
    max_frame_bytes: int = Field(default=MAX_FRAME_BYTES, ge=1024)

    max_bad_frames: int = Field(default=20, ge=1, description="before a connection is closed")

    agent_liveness_timeout_s: float = Field(
        default=3.0,
        gt=0,
        le=4.0,  # the newcomer waits this long for its welcome; our agent waits 5 s
        description="a second agent for a vehicle id takes it over only if the first "
        "sends nothing for this long after a ping; otherwise it is refused (close 4409)",
    )
