"""The hub's scan checks that need no socket: the rate limit counts the scans' own times."""

from __future__ import annotations

import asyncio
import dataclasses

from backend.realtime.bus import InProcessBus
from backend.scans.repository import ScanRepository
from backend.scans.service import ScanRejected, ScanService
from backend.storage.database import make_engine
from protocol.scans import encode_scan
from tests.support.scans import _frame

NOW = 1_760_000_000.0


def _service() -> ScanService:
    repository = ScanRepository(make_engine("sqlite:///:memory:"))
    return ScanService(repository, InProcessBus(), max_rate_hz=20.0, clock=lambda: NOW)


def _scan(seq: int, at: float) -> bytes:
    return encode_scan(dataclasses.replace(_frame(), seq=seq, utc_time=at))


async def _ingest(service: ScanService, scans: list[bytes]) -> int:
    reasons = []
    for data in scans:
        try:
            await service.ingest("v1", "s1", data)
        except ScanRejected as refusal:
            reasons.append(refusal.reason)
    assert set(reasons) <= {"rate"}
    return len(reasons)


def test_a_burst_of_a_10_hz_sensors_scans_after_a_stall_is_not_too_many() -> None:
    # Three seconds of a 10 Hz sensor, read at one instant (the hub's store held it up).
    scans = [_scan(i, NOW - 3.0 + i * 0.1) for i in range(30)]
    assert asyncio.run(_ingest(_service(), scans)) == 0


def test_more_than_20_scans_a_second_of_the_sensors_time_are_refused() -> None:
    scans = [_scan(i, NOW - 1.0 + i * 0.02) for i in range(50)]  # a second at 50 Hz
    service = _service()
    assert asyncio.run(_ingest(service, scans)) == 30  # 20 in the second pass
    assert service.diagnostics_of("v1").rejected["rate"] == 30
