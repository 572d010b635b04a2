"""Telemetry with a physically impossible value (latitude 91, an altitude of 1e308): the
hub refuses the sample, counts it by reason in /metrics, never stores or shows it, and
keeps the agent's link, whose next good sample is stored. A flight's export is never a
silently empty file."""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from sqlalchemy import Engine, insert

from backend.api.logs import exports
from backend.realtime.bus import ReliableSubscription
from backend.storage.database import make_engine, migrate
from backend.storage.logbook import Logbook
from backend.storage.models import FlightRow
from backend.storage.records import StoredRecord, TelemetryEnvelope
from backend.storage.repository import Repository
from backend.storage.writer import StorageWriter
from protocol.messages import STATE_BOUNDS, LiveState, Telemetry, VehicleState, encode
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import ScriptedAgent, scripted_agent
from tests.support.api import access_token, api_client
from tests.support.hellos import agent_hello
from tests.support.hub_server import running_hub
from tests.support.mavutil_state import mavutil_in_mavlink2, read_tlog
from tests.support.metrics import _metrics, _value
from tests.support.waiting import poll_until

Enrol = Callable[[str], str]
HOME = (-35.363262, 149.165237)


def _state(**changes: Any) -> VehicleState:
    values: dict[str, Any] = {
        "armed": True,
        "mode": "GUIDED",
        "lat": HOME[0],
        "lon": HOME[1],
        "alt_rel": 10.0,
        "alt_msl": 594.0,
        "groundspeed": 3.0,
        "heading_deg": 90.0,
        "battery_voltage": 16.2,
        "battery_remaining": 80.0,
        "gps_fix": 3,
        "satellites": 10,
    }
    return VehicleState(**(values | changes))


def _send(agent: ScriptedAgent, seq: int, state: VehicleState) -> None:
    agent.send(encode(Telemetry(seq=seq, time=time.time(), state=state)))


def _stored(api: httpx.Client) -> list[dict[str, Any]]:
    page = api.get("/api/v1/vehicles/v1/telemetry", params={"start": 0, "limit": 100})
    samples: list[dict[str, Any]] = page.json()["samples"]
    return samples


def _acked_up_to(agent: ScriptedAgent, seq: int) -> None:
    """Read the hub's frames until an ack covers ``seq`` (the hub asks for nothing)."""
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        frame = json.loads(agent.recv(timeout=max(0.0, deadline - time.monotonic())))
        assert frame["type"] != "resend", f"the hub asked for a refused sample again: {frame}"
        if frame["type"] == "ack" and (frame.get("telemetry_seq") or -1) >= seq:
            return
    raise AssertionError(f"no ack up to {seq}")


def test_impossible_samples_are_refused_counted_and_the_link_goes_on(
    hub: str, enrol: Enrol, admin_token: str
) -> None:
    series = {
        field: f'gcs_telemetry_refused_total{{reason="{field}_out_of_range"}}'
        for field in ("lat", "alt_msl", "battery_remaining", "groundspeed")
    }
    before = _metrics(hub, admin_token)
    with (
        scripted_agent(hub, "v1", enrol("v1"), delivery=True) as agent,
        api_client(hub, admin_token) as api,
    ):
        _send(agent, 0, _state())
        _send(agent, 1, _state(lat=91.0))
        _send(agent, 2, _state(alt_msl=1e308))
        _send(agent, 3, _state(battery_remaining=250.0))
        _send(agent, 4, _state(groundspeed=-3.0))
        _send(agent, 5, _state(alt_rel=12.0))
        # every number accounted for: acked past the refused ones, none asked for again
        _acked_up_to(agent, 5)
        poll_until(lambda: len(_stored(api)) >= 2, 10, "the good samples stored")
        stored = _stored(api)
        assert [s["alt_rel"] for s in stored] == [10.0, 12.0]
        assert all(s["lat"] == HOME[0] for s in stored)
        assert api.get("/api/v1/vehicles/v1").json()["state"]["alt_rel"] == 12.0
        after = _metrics(hub, admin_token)
        for field, name in series.items():
            assert _value(after, name) == _value(before, name) + 1, field
        events = api.get("/api/v1/events", params={"vehicle_id": "v1", "kind": "data_lost"})
        texts = [e["text"] for e in events.json()["events"]]
        assert len(texts) == 1, texts
        assert texts[0].startswith("telemetry samples 1-4 of stream s1 were refused, not stored")
        assert "lat 91 is outside -90..90" in texts[0]
        # the link survived all of it
        _send(agent, 6, _state(alt_rel=13.0))
        _acked_up_to(agent, 6)
        poll_until(lambda: len(_stored(api)) == 3, 10, "the next good sample stored")
        # a live state (shown, never stored) is held to the same bounds
        lat = series["lat"]
        agent.send(encode(LiveState(time=time.time(), state=_state(lat=-91.0, alt_rel=20.0))))
        agent.send(encode(LiveState(time=time.time(), state=_state(alt_rel=21.0))))
        poll_until(
            lambda: api.get("/api/v1/vehicles/v1").json()["state"]["alt_rel"] == 21.0,
            10,
            "the good live state shown",
        )
        assert _value(_metrics(hub, admin_token), lat) == _value(before, lat) + 2


def test_every_bound_is_a_number_of_the_vehicle_state() -> None:
    fields = VehicleState.model_fields
    for name, (low, high) in STATE_BOUNDS.items():
        assert name in fields, name
        assert low < high, name


def _store(engine: Engine, records: list[StoredRecord]) -> None:
    """Through the real writer, as a hub that took such samples stored them."""
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


def test_a_flight_holding_impossible_samples_exports_them_and_an_empty_one_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Samples stored before the hub refused them (an altitude of 1e308): packing it
    raised inside the .tlog export, which answered 200 with an empty file."""
    url = f"sqlite:///{tmp_path}/store.sqlite3"
    engine = make_engine(url)
    start = time.time() - 60
    states = [_state(armed=False)] + [_state(alt_msl=1e308, alt_rel=1e308)] * 3
    states += [_state(lat=91.0), _state(armed=False)]
    records: list[StoredRecord] = [
        TelemetryEnvelope("v1", "s", Telemetry(seq=i, time=start + i, state=s))
        for i, s in enumerate(states)
    ]
    try:
        _store(engine, records)
        flight_id = Logbook(engine).flights("v1", None, 1)[0].id
        with engine.begin() as connection:  # a flight whose telemetry was pruned
            connection.execute(
                insert(FlightRow).values(
                    vehicle_id="v1", start_time=start - 3600, end_time=start - 3500
                )
            )
        empty_id = max(f.id for f in Logbook(engine).flights("v1", None, 10))
    finally:
        engine.dispose()
    with (
        running_hub(hub_settings(tmp_path, database_url=url)) as base,
        api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api,
    ):
        response = api.get(f"/api/v1/flights/{flight_id}/export.tlog")
        assert response.status_code == 200, response.text
        path = tmp_path / "flight.tlog"
        path.write_bytes(response.content)
        for format in ("tlog", "csv", "geojson"):
            empty = api.get(f"/api/v1/flights/{empty_id}/export.{format}")
            assert empty.status_code == 409, empty.text
            assert empty.json()["detail"] == f"flight {empty_id} has no telemetry stored to export"

        def failing(*_: object) -> Iterator[bytes]:
            raise OverflowError("float too large to pack with f format")
            yield b""  # a generator, as the exporters are

        monkeypatch.setattr(exports, "tlog_chunks", failing)
        failed = api.get(f"/api/v1/flights/{flight_id}/export.tlog")
        assert failed.status_code == 500, failed.text
        assert failed.json()["detail"].startswith(
            f"flight {flight_id}'s .tlog could not be written"
        )
    messages = read_tlog(mavutil_in_mavlink2(monkeypatch), path)
    kinds = [m.get_type() for m in messages]
    # the samples of the flight (armed), each written; the one at latitude 91 without a place
    assert kinds.count("VFR_HUD") == kinds.count("SYS_STATUS") >= 4
    positions = [m for m in messages if m.get_type() == "GLOBAL_POSITION_INT"]
    assert len(positions) == kinds.count("VFR_HUD") - 1
    assert {p.alt for p in positions} >= {2**31 - 1}  # clamped to the field, not dropped
