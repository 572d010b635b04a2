"""Delivery between agent and hub, frame by frame: acks after storage, gaps asked for,
losses recorded, duplicates dropped. A scripted agent plays the agent's side."""

from __future__ import annotations

import time
from collections.abc import Callable

import httpx

from protocol.messages import Event, LiveState, Telemetry, Unavailable, VehicleState, encode
from tests.support.agents import scripted_agent, telemetry_frame
from tests.support.delivery import _acked, _next

Enrol = Callable[[str], str]


def test_gap_is_asked_for_filled_and_then_acknowledged(
    hub: str, enrol: Enrol, admin_api: httpx.Client
) -> None:
    with scripted_agent(hub, "gappy", enrol("gappy"), delivery=True) as agent:
        for seq in (0, 1, 2, 5):
            agent.send(telemetry_frame(seq))
        resend = _next(agent, lambda frame: frame["type"] == "resend")
        assert (resend["kind"], resend["first_seq"], resend["last_seq"]) == ("telemetry", 3, 4)
        assert resend["stream_id"] == "s1"
        # Until the gap is filled, the hub acknowledges only what has no hole below it.
        for seq in (3, 4, 1):  # 1 again: a duplicate, as a replay would send it
            agent.send(telemetry_frame(seq, alt=99.0))
        _next(agent, _acked("telemetry", 5))
    stored = admin_api.get("/api/v1/vehicles/gappy/telemetry")
    assert stored.status_code == 200, stored.text
    samples = stored.json()["samples"]
    assert sorted(s["seq"] for s in samples) == [0, 1, 2, 3, 4, 5]
    assert next(s for s in samples if s["seq"] == 1)["alt_rel"] == 1.0  # the first copy


def test_frames_the_vehicle_no_longer_has_are_recorded_as_lost(
    hub: str, enrol: Enrol, admin_api: httpx.Client
) -> None:
    with scripted_agent(hub, "lossy", enrol("lossy"), delivery=True) as agent:
        agent.send(telemetry_frame(0))
        agent.send(telemetry_frame(9))
        _next(agent, lambda frame: frame["type"] == "resend" and frame["first_seq"] == 1)
        lost = Unavailable(
            stream_id="s1", kind="telemetry", first_seq=1, last_seq=8, reason="outbox full"
        )
        agent.send(encode(lost))
        _next(agent, _acked("telemetry", 9))
        # Events are numbered and acknowledged on their own.
        agent.send(encode(Event(seq=0, time=time.time(), kind="statustext", text="hello")))
        _next(agent, _acked("event", 0))
    events = admin_api.get("/api/v1/events", params={"vehicle_id": "lossy", "kind": "data_lost"})
    texts = [event["text"] for event in events.json()["events"]]
    assert texts == ["telemetry samples 1-8 of stream s1 never arrived: outbox full"]


def test_a_live_state_keeps_a_replayed_backlog_off_the_live_view(
    hub: str, enrol: Enrol, admin_api: httpx.Client
) -> None:
    now = time.time()
    with scripted_agent(hub, "catching-up", enrol("catching-up"), delivery=True) as agent:
        live = LiveState(time=now, state=VehicleState(alt_rel=50.0))
        agent.send(encode(live))
        for seq in range(5):  # an hour-old backlog, replayed after the live state
            old = Telemetry(seq=seq, time=now - 3600 + seq, state=VehicleState(alt_rel=1.0))
            agent.send(encode(old))
        _next(agent, _acked("telemetry", 4))
    vehicle = admin_api.get("/api/v1/vehicles/catching-up").json()
    assert vehicle["state"]["alt_rel"] == 50.0, "the live view kept the vehicle as it is now"
    assert vehicle["last_seen"] == now
    stored = admin_api.get(
        "/api/v1/vehicles/catching-up/telemetry", params={"start": now - 4000}
    ).json()["samples"]
    assert [s["seq"] for s in stored] == [0, 1, 2, 3, 4], "the backlog is stored all the same"
