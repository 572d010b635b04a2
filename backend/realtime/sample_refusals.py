"""Telemetry samples an agent reported with a physically impossible value: refused one by
one, the link kept.

A refused sample is never stored or shown, but its sequence number is accounted for: the
store records it as refused (a ``data_lost`` event saying why), so the hole closes, the
agent's acknowledgements move past it, and it is not asked for again and again. A run of
consecutive refused samples is recorded once per interval, and refusals are logged at
most once per interval, not per sample: a sensor stuck on a bad value at 10 Hz must not
flood the flight log or the hub's log.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

from backend.observability.metrics import TELEMETRY_REFUSED
from backend.storage.records import LostFrames

log = logging.getLogger(__name__)

RECORD_INTERVAL_S = 1.0


@dataclass
class _Run:
    stream_id: str
    first_seq: int
    last_seq: int
    reason: str  # the first sample's
    started: float


class SampleRefusals:
    """One agent session's refused samples, gathered into runs."""

    def __init__(
        self,
        vehicle_id: str,
        interval_s: float = RECORD_INTERVAL_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._vehicle_id = vehicle_id
        self._interval_s = interval_s
        self._clock = clock
        self._run: _Run | None = None
        self._logged_at: float | None = None
        self._unlogged = 0  # samples refused since the last log line

    def count(self, problems: list[tuple[str, str]], what: str) -> str:
        """Count one refused sample (``what`` it was, for the log); the reason, said."""
        TELEMETRY_REFUSED.labels(reason=f"{problems[0][0]}_out_of_range").inc()
        reason = "; ".join(problem for _, problem in problems)
        now = self._clock()
        self._unlogged += 1
        if self._logged_at is None or now - self._logged_at >= self._interval_s:
            log.warning(
                "refused %d sample(s) of %s since the last report, the last (%s): %s",
                self._unlogged,
                self._vehicle_id,
                what,
                reason,
            )
            self._logged_at, self._unlogged = now, 0
        return reason

    def refuse(
        self, stream_id: str, seq: int, problems: list[tuple[str, str]]
    ) -> LostFrames | None:
        """Count one refused telemetry sample; the run to record when this one does not
        extend it (another stream, a number out of order, or the interval has passed)."""
        reason = self.count(problems, f"telemetry {seq} of stream {stream_id}")
        now = self._clock()
        run = self._run
        if (
            run is not None
            and run.stream_id == stream_id
            and seq == run.last_seq + 1
            and now - run.started < self._interval_s
        ):
            run.last_seq = seq
            return None
        done = self.flush()
        self._run = _Run(stream_id, seq, seq, reason, now)
        return done

    def flush(self) -> LostFrames | None:
        """The run gathered so far, to record (before the next good sample is stored, so
        that the store never sees it as a hole); None without one."""
        run, self._run = self._run, None
        if run is None:
            return None
        return LostFrames(
            self._vehicle_id,
            run.stream_id,
            "telemetry",
            run.first_seq,
            run.last_seq,
            f"a value is impossible ({run.reason})",
            refused=True,
        )
