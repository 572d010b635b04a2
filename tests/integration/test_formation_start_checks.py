"""A formation's start and join through the real hub, with scripted agents on real
WebSockets: members that are not flying are refused by name before any of them is told
anything, and a formation that does not form in time ends with the reason, every member
told to leave (its agent then holds)."""

from __future__ import annotations

import json
import re
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import httpx
import pytest

from common.geodesy import LocalFrame
from protocol.messages import LandedState, Telemetry, VehicleState, encode
from tests.conftest import hub_settings
from tests.support.agents import ScriptedAgent, scripted_agent
from tests.support.api import api_client
from tests.support.hub_server import running_hub
from tests.support.waiting import poll_until

Enrol = Callable[[str], str]
SITE = LocalFrame(-35.363262, 149.165237)
JOIN_TIMEOUT_S = 1.0


@pytest.fixture
def hub(tmp_path: Path) -> Iterator[str]:
    """A hub that gives a formation one second to form."""
    settings = hub_settings(tmp_path, formation_join_timeout_s=JOIN_TIMEOUT_S)
    with running_hub(settings) as base_url:
        yield base_url


def _state(
    north: float, east: float, landed: LandedState | None, armed: bool = True
) -> VehicleState:
    lat, lon = SITE.to_geo(east, north)
    return VehicleState(
        mode="GUIDED",
        armed=armed,
        landed_state=landed,
        lat=lat,
        lon=lon,
        alt_rel=10.0 if landed != "on_ground" else 0.0,
        alt_msl=594.0,
        home_lat=SITE.origin.lat,
        home_lon=SITE.origin.lon,
        home_alt_msl=584.0,
        battery_remaining=95.0,
        battery_voltage=16.0,
        gps_fix=3,
        satellites=12,
        ready_to_fly=True,
    )


def _report(
    api: httpx.Client, agent: ScriptedAgent, vehicle: str, seq: int, state: VehicleState
) -> None:
    agent.send(encode(Telemetry(seq=seq, time=time.time(), state=state)))
    poll_until(
        lambda: (
            api.get(f"/api/v1/vehicles/{vehicle}").json()["state"]
            == json.loads(state.model_dump_json())
        ),
        10,
        f"{vehicle}'s sample {seq} in the hub's live state",
        every_s=0.02,
    )


def _request(leader: str | None, followers: list[str]) -> dict[str, Any]:
    route = []
    for north in (0.0, 20.0):
        lat, lon = SITE.to_geo(0.0, north)
        route.append({"lat": lat, "lon": lon, "alt_m": 10.0})
    return {
        "leader_id": leader,
        "route": route,
        "speed_ms": 2.0,
        "followers": [{"vehicle_id": v} for v in followers],
        "shape": "line",
        "spacing_m": 3.0,
        "min_separation_m": 2.0,
    }


def _next_formation_frame(agent: ScriptedAgent) -> dict[str, Any]:
    """The next frame the hub sends this agent (acks and resend requests read past)."""
    frame = agent.recv(timeout=10)
    assert isinstance(frame, str)
    message: dict[str, Any] = json.loads(frame)
    return message


def test_members_not_flying_are_refused_by_name_before_any_is_told(
    hub: str, enrol: Enrol, admin_token: str
) -> None:
    """A grounded, disarmed member (or one whose landed state is unknown) was accepted,
    every member switched to GUIDED, and the formation sat joining for ever."""
    names = ["sim_1", "sim_2", "sim_3"]
    with ExitStack() as stack, api_client(hub, admin_token) as api:
        agents = {v: stack.enter_context(scripted_agent(hub, v, enrol(v))) for v in names}
        _report(api, agents["sim_1"], "sim_1", 1, _state(0, 0, "in_air"))
        _report(api, agents["sim_2"], "sim_2", 1, _state(0, 3, None))
        _report(api, agents["sim_3"], "sim_3", 1, _state(0, 6, "on_ground", armed=False))

        refused = api.post("/api/v1/formations", json=_request("sim_1", ["sim_2", "sim_3"]))
        assert refused.status_code == 422, refused.text
        detail = refused.json()["detail"]
        assert "sim_2: its landed state is unknown" in detail[0]["msg"], detail
        assert "sim_3 is on the ground: take off first" in detail[0]["msg"], detail
        assert "sim_1" not in detail[0]["msg"]
        assert api.get("/api/v1/formations").json()["formations"] == []

        # Once they fly it starts; the first frame each agent gets is its slot in this
        # formation, so the refusal sent none of them anything.
        _report(api, agents["sim_2"], "sim_2", 2, _state(0, 3, "in_air"))
        _report(api, agents["sim_3"], "sim_3", 2, _state(0, 6, "takeoff"))
        started = api.post("/api/v1/formations", json=_request("sim_1", ["sim_2", "sim_3"]))
        assert started.status_code == 200, started.text
        for vehicle, agent in agents.items():
            first = _next_formation_frame(agent)
            assert first["type"] == "formation", (vehicle, first)
            assert first["formation_id"] == started.json()["id"]


def test_a_formation_that_does_not_form_in_time_ends_naming_who_is_not_in_place(
    hub: str, enrol: Enrol, admin_token: str
) -> None:
    """Followers 35 m from their slots: after the time limit the formation ends with the
    reason, and every follower is told to leave it (its agent holds where it is)."""
    followers = ["sim_2", "sim_3"]
    with ExitStack() as stack, api_client(hub, admin_token) as api:
        agents = {v: stack.enter_context(scripted_agent(hub, v, enrol(v))) for v in followers}
        _report(api, agents["sim_2"], "sim_2", 1, _state(35, 0, "in_air"))
        _report(api, agents["sim_3"], "sim_3", 1, _state(35, 3, "in_air"))
        started = api.post("/api/v1/formations", json=_request(None, followers))
        assert started.status_code == 200, started.text
        formation_id = started.json()["id"]
        assert started.json()["formed_at"] is None

        deadline = time.monotonic() + JOIN_TIMEOUT_S + 10
        for agent in agents.values():
            frame = _next_formation_frame(agent)
            while frame["type"] != "formation_end":  # its slot, then the leader's states
                assert time.monotonic() < deadline, "the formation did not end"
                frame = _next_formation_frame(agent)
            assert frame["formation_id"] == formation_id
            reason = frame["reason"]
            assert reason.startswith(f"did not form within {JOIN_TIMEOUT_S:g} s: "), reason
            for follower in followers:
                far = re.search(rf"{follower} is (\d+\.\d) m from its slot", reason)
                assert far is not None, reason
                assert 30 < float(far[1]) < 40, reason
        status = api.get(f"/api/v1/formations/{formation_id}").json()
        assert status["stopped"] == reason
        assert status["formed_at"] is None
        stored = api.get("/api/v1/formations").json()["formations"]
        assert [(f["id"], f["stop_reason"]) for f in stored] == [(formation_id, reason)]
