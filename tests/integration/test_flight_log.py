"""The flight log on both databases: flights found, downsampling, exports, bad input."""

from __future__ import annotations

import asyncio
import csv
import io
import json
import math
import time
from pathlib import Path
from typing import get_args

import httpx
import pytest
from sqlalchemy import Engine

from backend.realtime.bus import ReliableSubscription
from backend.storage.database import migrate
from backend.storage.logbook import Logbook
from backend.storage.models import EventRow, FlightRow
from backend.storage.records import StoredRecord, TelemetryEnvelope
from backend.storage.repository import Repository
from backend.storage.retention import RetentionPolicy
from backend.storage.writer import StorageWriter
from protocol.messages import EventKind, Telemetry, VehicleState
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import access_token, api_client
from tests.support.hellos import agent_hello
from tests.support.hub_server import running_hub
from tests.support.mavutil_state import mavutil_in_mavlink2, read_tlog

HOME = (-35.363262, 149.165237)
HOUR_AT_10HZ = 36_000


def _sample(
    seq: int,
    t: float,
    armed: bool,
    alt: float,
    mode: str = "GUIDED",
    north_m: float = 0.0,
    battery: float = 100.0,
) -> TelemetryEnvelope:
    lat = HOME[0] + north_m / 111_320
    state = VehicleState(
        armed=armed,
        mode=mode,
        lat=lat,
        lon=HOME[1],
        alt_rel=alt,
        alt_msl=584 + alt,
        groundspeed=5.0,
        heading_deg=0.0,
        battery_remaining=battery,
        gps_fix=3,
        satellites=10,
    )
    return TelemetryEnvelope("v1", "s", Telemetry(seq=seq, time=t, state=state))


def _flight_samples(start: float) -> list[TelemetryEnvelope]:
    """On the ground, a 100 m flight north at 10 m altitude, a landing, a disarm."""
    samples = [_sample(0, start, False, 0.0, mode="STABILIZE")]
    samples += [
        _sample(1 + i, start + 1 + i, True, min(10.0, i * 2.0), north_m=i * 5.0, battery=100 - i)
        for i in range(21)
    ]
    samples += [_sample(22, start + 23, False, 0.0, mode="LAND", north_m=100.0, battery=79)]
    return samples


def _store(engine: Engine, records: list[StoredRecord]) -> None:
    """Through the real writer: queue everything, stop it, and its shutdown flush stores it."""
    migrate(engine)
    Repository(engine).upsert_vehicle(agent_hello(system_id=3), now=0)

    async def scenario() -> None:
        queue = ReliableSubscription(len(records) + 1)
        writer = StorageWriter(Repository(engine), Logbook(engine), queue, 500, 0.05)
        for record in records:
            queue.offer("v1", record)
        task = asyncio.create_task(writer.run())
        await asyncio.sleep(0)  # let it start collecting before it is stopped
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task

    asyncio.run(scenario())


def test_a_flight_is_detected_from_arm_to_disarm(engine: Engine) -> None:
    _store(engine, list(_flight_samples(start=1000.0)))
    logbook = Logbook(engine)
    (flight,) = logbook.flights(None, None, 10)
    assert (flight.start_time, flight.end_time) == (1001.0, 1023.0)
    assert flight.duration_s == 22.0
    assert flight.max_alt_m == 10.0
    assert flight.distance_m == pytest.approx(100.0, rel=0.01)
    assert flight.battery_used_pct == 21.0  # 100 % at arming, 79 % at the disarm sample
    assert flight.samples == 22
    events = logbook.events("v1", None, None, None, None, 100)
    kinds = sorted(event.kind for event in events)
    assert kinds == ["armed", "disarmed", "mode", "mode"]
    assert {event.text for event in events if event.kind == "mode"} == {
        "mode STABILIZE → GUIDED",
        "mode GUIDED → LAND",
    }
    # Replaying the same samples (an agent resending after a reconnect) changes nothing.
    _store(engine, list(_flight_samples(start=1000.0)))
    assert logbook.count(FlightRow) == 1
    assert logbook.count(EventRow) == 4


def test_an_hour_at_10hz_downsamples_keeping_min_and_max(engine: Engine) -> None:
    migrate(engine)
    repository = Repository(engine)
    repository.upsert_vehicle(agent_hello(system_id=3), now=0)
    batch = []
    for i in range(HOUR_AT_10HZ):
        alt = 50 + 30 * math.sin(i / 900)
        if i == 12_345:
            alt = 151.5  # a one-sample spike that every-n-th sampling would miss
        if i == 23_456:
            alt = -2.25
        batch.append(_sample(i, 10_000 + i / 10, True, alt))
    for start in range(0, HOUR_AT_10HZ, 5000):
        repository.insert_telemetry(batch[start : start + 5000])
    rows = Logbook(engine).series("v1", 10_000, 10_000 + 3600, 1000, "alt_rel")
    altitudes = [row["alt_rel"] for row in rows]
    assert len(rows) == 1000
    assert max(altitudes) == 151.5
    assert min(altitudes) == -2.25
    times = [row["time"] for row in rows]
    assert times == sorted(times)


def _stored_flight(database_url: str) -> int:
    from backend.storage.database import make_engine

    engine = make_engine(database_url)
    try:
        _store(engine, list(_flight_samples(start=time.time() - 60)))
        return Logbook(engine).flights("v1", None, 1)[0].id
    finally:
        engine.dispose()


def test_exports_are_valid_and_tlog_reads_back(
    database_url: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    flight_id = _stored_flight(database_url)
    settings = hub_settings(tmp_path, database_url=database_url)
    with (
        running_hub(settings) as base,
        api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api,
    ):
        flights = api.get("/api/v1/flights").json()["flights"]
        assert [flight["id"] for flight in flights] == [flight_id]
        summary = api.get(f"/api/v1/flights/{flight_id}").json()
        assert summary["max_alt_m"] == 10.0

        csv_text = api.get(f"/api/v1/flights/{flight_id}/export.csv").text
        rows = list(csv.DictReader(io.StringIO(csv_text)))
        assert len(rows) == 22
        assert max(float(row["alt_rel"]) for row in rows) == 10.0

        geojson = api.get(f"/api/v1/flights/{flight_id}/export.geojson").json()
        assert geojson["type"] == "FeatureCollection"
        track = next(f for f in geojson["features"] if f["geometry"]["type"] == "LineString")
        assert len(track["geometry"]["coordinates"]) == 22

        response = api.get(f"/api/v1/flights/{flight_id}/export.tlog")
        assert response.headers["content-type"] == "application/octet-stream"
        path = tmp_path / "flight.tlog"
        path.write_bytes(response.content)
    messages = read_tlog(mavutil_in_mavlink2(monkeypatch), path)
    assert [m.get_type() for m in messages].count("GLOBAL_POSITION_INT") == 22


def test_flight_log_bad_input(hub: str, admin_api: httpx.Client) -> None:
    assert admin_api.get("/api/v1/flights", params={"vehicle_id": "ghost"}).status_code == 404
    assert admin_api.get("/api/v1/flights/424242").status_code == 404
    too_big = admin_api.get("/api/v1/events", params={"limit": 100_000})
    assert too_big.status_code == 422
    assert "limit" in json.dumps(too_big.json())
    backwards = admin_api.get("/api/v1/events", params={"start": 200, "end": 100})
    assert backwards.status_code == 422
    assert "start" in json.dumps(backwards.json())
    points = admin_api.get("/api/v1/telemetry/series", params={"points": 10**6})
    assert points.status_code == 422
    # An unknown event kind is refused naming the kinds, as the audit log's filters are.
    nonsense = admin_api.get("/api/v1/events", params={"kind": "nonsense"})
    assert nonsense.status_code == 422
    (problem,) = nonsense.json()["detail"]
    assert problem["loc"] == ["query", "kind"]
    for kind in get_args(EventKind):
        assert f"'{kind}'" in problem["msg"]
    assert admin_api.get("/api/v1/events", params={"kind": "mode"}).status_code == 200


def test_retention_removes_only_old_rows(engine: Engine) -> None:
    now = 100 * 86400.0
    _store(
        engine,
        list(_flight_samples(start=now - 10 * 86400))
        + [_sample(100 + i, now - 3600 + i, False, 0.0) for i in range(5)],
    )
    removed = Logbook(engine).apply_retention(RetentionPolicy(telemetry_days=7), now)
    assert removed == {"telemetry": 23, "scans": 0}  # scans go with telemetry
    assert Repository(engine).count_telemetry("v1") == 5
