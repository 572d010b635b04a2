"""Exactly-once delivery of telemetry and events between agent and hub: the hub's ack and
resend, the agent's word on frames it no longer has, and the stream a replayed frame
came from."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from protocol.messages.base import MAX_SEQ, Message, StreamId

ReplayedStream = Annotated[
    StreamId | None,
    Field(
        default=None,
        description="Set only on a frame replayed from an earlier agent run: that run's stream.",
    ),
]


SequencedKind = Literal["telemetry", "event"]


class Unavailable(Message):
    """The agent's answer to a resend it cannot serve: those frames were dropped when its
    outbox was full. The hub records the loss and stops waiting for them."""

    type: Literal["unavailable"] = "unavailable"
    stream_id: StreamId
    kind: SequencedKind
    first_seq: int = Field(ge=0, le=MAX_SEQ)
    last_seq: int = Field(ge=0, le=MAX_SEQ)
    reason: str = Field(max_length=200)


class Ack(Message):
    """Everything up to these sequence numbers of the stream is stored; the agent may
    forget it. Sent after the database commit, never on receipt."""

    type: Literal["ack"] = "ack"
    stream_id: StreamId
    telemetry_seq: int | None = Field(default=None, ge=0, le=MAX_SEQ)
    event_seq: int | None = Field(default=None, ge=0, le=MAX_SEQ)


class Resend(Message):
    """The hub saw a gap in a stream: send these frames again (or say they are gone)."""

    type: Literal["resend"] = "resend"
    stream_id: StreamId
    kind: SequencedKind
    first_seq: int = Field(ge=0, le=MAX_SEQ)
    last_seq: int = Field(ge=0, le=MAX_SEQ)
