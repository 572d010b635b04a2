"""Long STATUSTEXTs, joined from their chunks before they become events.

STATUSTEXT carries at most 50 characters. A longer text goes out in chunks that share a
non-zero ``id``, numbered from 0 by ``chunk_seq`` (PX4 does this; ArduPilot truncates).
The MAVLink rules: ``id`` 0 is a text complete in itself; a chunk whose text is shorter
than the field (the field holds a NUL) is the last one. A text that is an exact multiple
of 50 characters has no such chunk, and a chunk can be lost on the radio, so a set that
stays incomplete is let out as it stands after ``flush_after_s``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from vehicle_agents.fcu.messages import MavMessage

TEXT_FIELD_CHARS = 50  # STATUSTEXT.text is char[50]
MISSING = "…"  # stands in for a chunk that never came


@dataclass(frozen=True)
class StatusTextTimeouts:
    # PX4 sends a text's chunks back to back; a second covers a slow, busy radio link.
    flush_after_s: float = 1.0


@dataclass(frozen=True)
class JoinedText:
    severity: int
    text: str


def _whole(severity: int, text: str) -> JoinedText:
    """A whole text, without the whitespace an autopilot leaves at its end (PX4 ends some
    with a tab, which showed in the event feed and the flight log). Only the whole text
    is trimmed: a chunk may end in a space that belongs between two words."""
    return JoinedText(severity, text.rstrip())


@dataclass
class _Partial:
    severity: int
    started_at: float
    chunks: dict[int, str] = field(default_factory=dict)
    last_seq: int | None = None  # known once the chunk with the NUL has come

    def text(self) -> str:
        highest = self.last_seq if self.last_seq is not None else max(self.chunks)
        return "".join(self.chunks.get(seq, MISSING) for seq in range(highest + 1))

    def complete(self) -> bool:
        return self.last_seq is not None and len(self.chunks) == self.last_seq + 1


class StatusTextJoiner:
    """Feed it every STATUSTEXT, and the time now; it gives back whole texts."""

    def __init__(self, timeouts: StatusTextTimeouts | None = None) -> None:
        self.timeouts = timeouts or StatusTextTimeouts()
        self._partial: dict[int, _Partial] = {}

    def add(self, message: MavMessage, now: float) -> list[JoinedText]:
        """The texts this chunk completes (none, or one), after any that timed out."""
        done = self.due(now)
        raw = message.text
        text = raw.split("\x00", 1)[0]
        # pymavlink strips the NUL padding, so a short text is the sign of the last chunk
        last = "\x00" in raw or len(text) < TEXT_FIELD_CHARS
        text_id = int(getattr(message, "id", 0) or 0)
        if text_id == 0:
            done.append(_whole(int(message.severity), text))
            return done
        partial = self._partial.get(text_id)
        seq = int(getattr(message, "chunk_seq", 0) or 0)
        if partial is None or seq in partial.chunks:
            # a new text, or the id came round again with the old one unfinished
            if partial is not None:
                done.append(_whole(partial.severity, partial.text()))
            partial = self._partial[text_id] = _Partial(int(message.severity), now)
        partial.chunks[seq] = text
        if last:
            partial.last_seq = seq
        if partial.complete():
            del self._partial[text_id]
            done.append(_whole(partial.severity, partial.text()))
        return done

    def due(self, now: float) -> list[JoinedText]:
        """Incomplete texts whose wait is over, as far as they got."""
        expired = [
            text_id
            for text_id, partial in self._partial.items()
            if now - partial.started_at >= self.timeouts.flush_after_s
        ]
        return [self._release(text_id) for text_id in expired]

    def _release(self, text_id: int) -> JoinedText:
        partial = self._partial.pop(text_id)
        return _whole(partial.severity, partial.text())
