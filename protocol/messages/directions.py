"""The four directions of the wire, each one discriminated union (what a peer may send
that way), their adapters, and the JSON schema a client checks its types against."""

from __future__ import annotations

from typing import Annotated, Any, TypeAlias

from pydantic import Field, TypeAdapter

from protocol.messages.base import PROTOCOL_VERSION
from protocol.messages.codec import Decoder
from protocol.messages.commands import Command, CommandRequest, CommandResult
from protocol.messages.delivery import Ack, Resend, Unavailable
from protocol.messages.events import Event, EventBatch
from protocol.messages.fleet_feed import FleetSnapshot, VehicleBatch
from protocol.messages.formation import FormationEnd, FormationSlot, LeaderScan, LeaderUpdate
from protocol.messages.lidar_feed import (
    MapSubscriptions,
    ObstaclesUpdate,
    PointMapUpdate,
    ScanSubscriptions,
    SubscribeMap,
    SubscribeScans,
    UnsubscribeMap,
    UnsubscribeScans,
)
from protocol.messages.manual import (
    ControlRequest,
    LeaseRefusal,
    LeaseState,
    ManualApplied,
    ManualEcho,
    ManualFrame,
    ManualInput,
)
from protocol.messages.session import ErrorReply, Ping, Pong, Welcome
from protocol.messages.surveys import SurveyUpdate
from protocol.messages.telemetry import Hello, LiveState, ModeList, ScanSourceStats, Telemetry
from protocol.scans import scan_frame_schema

AgentToHub: TypeAlias = Annotated[
    Hello
    | Telemetry
    | LiveState
    | Event
    | CommandResult
    | Unavailable
    | Pong
    | ManualApplied
    | ScanSourceStats
    | ModeList,
    Field(discriminator="type"),
]
HubToAgent: TypeAlias = Annotated[
    Welcome
    | CommandRequest
    | Ack
    | Resend
    | ErrorReply
    | Ping
    | ManualFrame
    | FormationSlot
    | FormationEnd
    | LeaderUpdate
    | LeaderScan,
    Field(discriminator="type"),
]
ClientToHub: TypeAlias = Annotated[
    Ping
    | ControlRequest
    | ManualInput
    | SubscribeScans
    | UnsubscribeScans
    | SubscribeMap
    | UnsubscribeMap,
    Field(discriminator="type"),
]
HubToClient: TypeAlias = Annotated[
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

# One decoder per direction: every receiver of that direction decodes with it.
agent_to_hub: Decoder[AgentToHub] = Decoder(AgentToHub)
hub_to_agent: Decoder[HubToAgent] = Decoder(HubToAgent)
client_to_hub: Decoder[ClientToHub] = Decoder(ClientToHub)
hub_to_client: Decoder[HubToClient] = Decoder(HubToClient)
# A command on its own: the REST body's schema, and the commands' part of the docs.
command_adapter: TypeAdapter[Command] = TypeAdapter(Command)


def json_schema() -> dict[str, Any]:
    """Everything a client needs to check its types against."""
    return {
        "protocol": PROTOCOL_VERSION,
        "agent_to_hub": agent_to_hub.json_schema(),
        "hub_to_agent": hub_to_agent.json_schema(),
        "client_to_hub": client_to_hub.json_schema(),
        "hub_to_client": hub_to_client.json_schema(),
        # LIDAR scans: binary WebSocket frames, not JSON (protocol/scans.py)
        "scan_frame": scan_frame_schema(),
    }
