"""What hubs say to each other over NATS about a command for an agent that another hub
holds (backend/realtime/routing.py): the command, who sent it, and the answer.

A routed command names its sender: the hub that carries it out looks the sender's token
up in the shared database, checks the permission again, and writes the audit row and the
command log itself. A message on a command subject without a sender, or naming one the
database does not know, is refused before anything reaches the agent.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from protocol.messages import Command, CommandOutcome

NAME_MAX = 64  # a username (backend.settings' admin_username pattern) or a token's name


class RoutedSender(BaseModel):
    """The user a routed command comes from: the token they used, as the asking hub
    resolved it. Only an identity to check: the carrying hub rebuilds the permissions
    from the database, never from this message."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: str = Field(min_length=1, max_length=NAME_MAX)
    role: str = Field(min_length=1, max_length=16)
    token_id: int = Field(ge=1)
    token_kind: Literal["session", "access", "api"]


class RoutedCommand(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    command: Command
    timeout_s: float = Field(gt=0, le=600)
    sender: RoutedSender
    # The asking hub's source ("api", "ws", "survey"...), its id, and what its checks
    # found (safety rails, an override): copied into the carrying hub's audit row.
    source: str = Field(default="api", max_length=64)
    asked_by: str = Field(default="", max_length=64)
    checks: dict[str, Any] = Field(default_factory=dict)


RoutedError = Literal["offline", "timeout", "failed", "refused"]


class RoutedAnswer(BaseModel):
    outcome: CommandOutcome | None = None
    error: RoutedError | None = None
    message: str = ""
    # The carrying hub wrote the audit row and the command log entry: the asker must not
    # write them again (false: nothing was carried out, the asker records the refusal).
    recorded: bool = False
