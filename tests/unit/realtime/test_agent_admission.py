"""The vehicle-id rule's verdicts; the real sockets are in test_vehicle_id_clash."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass

from backend.realtime.agent_admission import MAX_CLOSE_REASON_BYTES, Clash, Takeover, judge


@dataclass
class Holder:
    stream_id: str | None
    answers: bool
    peer: str = "10.0.0.7:40000"
    asked: int = 0

    async def answers_within(self, timeout_s: float) -> bool:
        self.asked += 1
        return self.answers


def test_the_same_run_replaces_its_connection_without_asking() -> None:
    holder = Holder("run-a", answers=True)
    verdict = asyncio.run(judge(holder, "v1", "run-a", "10.0.0.7:40001", 3.0))
    assert isinstance(verdict, Takeover)
    assert holder.asked == 0


def test_another_run_is_refused_while_the_first_answers() -> None:
    long_id = "x" * 64
    verdict = asyncio.run(judge(Holder("run-a", True), long_id, "run-b", "10.0.0.8:1", 3.0))
    assert isinstance(verdict, Clash)
    assert len(verdict.reason.encode()) <= MAX_CLOSE_REASON_BYTES  # fits a close frame
    assert "clash" in verdict.reason
    assert "10.0.0.8:1" in verdict.event
    assert "10.0.0.7:40000" in verdict.event


def test_another_run_takes_over_a_silent_connection() -> None:
    verdict = asyncio.run(judge(Holder("run-a", False), "v1", "run-b", "10.0.0.8:1", 3.0))
    assert isinstance(verdict, Takeover)
