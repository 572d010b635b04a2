"""Frames in and out: one decoder per direction, which parses and validates a frame and
names the problem when it refuses one, and the encoder."""

from __future__ import annotations

import json
from typing import Any, Generic, Literal, TypeVar

from pydantic import TypeAdapter, ValidationError

from protocol.messages.base import Message
from protocol.messages.session import ErrorReply

T = TypeVar("T")


class ProtocolError(ValueError):
    """A frame that does not parse or validate; ``code`` goes into the ErrorReply.
    ``parsed`` is the frame's JSON object when it was one (and only its content was
    refused): what a receiver can still answer from, without parsing the frame again."""

    def __init__(
        self,
        code: Literal["bad_frame", "invalid_message"],
        message: str,
        parsed: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(message)
        self.code = code
        self.message = message
        self.parsed = parsed

    def reply(self) -> ErrorReply:
        return ErrorReply(code=self.code, message=self.message)


def describe_validation_error(error: ValidationError) -> str:
    """Name each offending field, e.g. ``state.lat: Input should be a valid number``."""
    parts = []
    for item in error.errors(include_url=False):
        location = ".".join(str(part) for part in item["loc"]) or "(message)"
        parts.append(f"{location}: {item['msg']}")
    return "; ".join(parts)


class Decoder(Generic[T]):
    """One direction's decoder (`protocol.messages.directions` makes the four): the only
    way a frame of that direction becomes a message, for whoever receives it.

    A valid frame is parsed and validated in one pass (pydantic-core's own JSON parser:
    2.5 times as fast as json.loads, then validation, on a telemetry frame;
    bench/bench_codec.py). A frame it refuses takes a second, slower pass that names the
    problem."""

    def __init__(self, union: Any) -> None:
        self.adapter: TypeAdapter[T] = TypeAdapter(union)

    def decode(self, frame: str | bytes) -> T:
        """Parse one frame, raising ProtocolError with a message that names the problem."""
        try:
            return self.adapter.validate_json(frame)
        except ValidationError:
            pass
        try:
            raw = json.loads(frame)
        except (ValueError, RecursionError) as error:
            # ValueError covers JSONDecodeError, UnicodeDecodeError and an integer over the
            # interpreter's digit limit; RecursionError, nesting deeper than the parser goes.
            raise ProtocolError("bad_frame", f"frame is not valid JSON: {error}") from None
        if not isinstance(raw, dict) or "type" not in raw:
            raise ProtocolError(
                "invalid_message", "frame must be a JSON object with a 'type' field"
            )
        try:
            return self.adapter.validate_python(raw)
        except ValidationError as error:
            raise ProtocolError(
                "invalid_message", describe_validation_error(error), parsed=raw
            ) from None

    def json_schema(self) -> dict[str, Any]:
        return self.adapter.json_schema()


def encode(message: Message) -> str:
    return message.model_dump_json()
