"""A formation through the hub: real hub, simulator and agent processes on loopback.

The leader (a vehicle) flies a square; the hub relays its state at 10 Hz to the
followers' agents, which send SET_POSITION_TARGET_GLOBAL_INT with velocity feed-forward.
The simulators run at real time: the leader's samples are stamped and predicted on the
wall clock, as they would be in the field.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from typing import Any

import httpx
import pytest

from backend.formation.route import LeaderRoute
from common.formation import LeaderState, Offset, OffsetFrame, slot_target
from common.geodesy import LocalFrame
from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client, send_command
from tests.support.formations import (
    ALTITUDES,
    LEADER,
    LEFT,
    MIN_SEPARATION_M,
    PAUSE_S,
    RIGHT,
    SIDE_M,
    SPEED_MS,
    _request,
    take_off_all,
)
from tests.support.processes import running_fleet
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready

pytestmark = [pytest.mark.integration, pytest.mark.slow]


@pytest.fixture(scope="module")
def airborne(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[LocalFleet, str]]:
    with running_fleet(tmp_path_factory.mktemp("formation"), vehicles=3, speedup=1.0) as fleet:
        base = fleet.plan.hub_http
        token = access_token(base, "admin", fleet.plan.admin_password)
        with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
            take_off_all(watcher, api, ALTITUDES)
        yield fleet, token


def _local(frame: LocalFrame, state: dict[str, Any]) -> tuple[float, float, float]:
    east, north = frame.to_local(state["lat"], state["lon"])
    return north, east, state["alt_rel"]


def test_bad_formations_are_refused_with_reasons(airborne: tuple[LocalFleet, str]) -> None:
    fleet, token = airborne
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(LEADER), 10, "the fleet")
        here = watcher.state(LEADER)
        frame = LocalFrame(here["lat"], here["lon"])
        cases = [
            ({"followers": [{"vehicle_id": LEADER}]}, "sim_1 cannot lead and follow"),
            ({"spacing_m": 1.0}, "minimum separation is 2 m"),
            ({"speed_ms": 9.0}, "above the vehicles' limit"),
        ]
        for overrides, reason in cases:
            answer = api.post("/api/v1/formations", json=_request(frame, **overrides))
            assert answer.status_code == 422, answer.text
            assert reason in answer.text


def _start_formed(
    api: httpx.Client, watcher: FleetWatcher, **overrides: Any
) -> tuple[str, LocalFrame]:
    """Every member in GUIDED, a formation started around the leader, and its followers
    in their slots; its id and the route's frame."""
    for vehicle in ALTITUDES:
        assert send_command(api, vehicle, name="set_mode", mode="GUIDED")["status"] == "accepted"
    here = watcher.state(LEADER)
    frame = LocalFrame(here["lat"], here["lon"])
    answer = api.post("/api/v1/formations", json=_request(frame, **overrides))
    assert answer.status_code == 200, answer.text
    formation_id: str = answer.json()["id"]
    poll_until(
        lambda: api.get(f"/api/v1/formations/{formation_id}").json()["formed_at"],
        60,
        "the followers in their slots",
    )
    return formation_id, frame


def _formation_events(watcher: FleetWatcher, text: str) -> Callable[[Any], bool]:
    return lambda v: any(e.get("kind") == "formation" and text in e["text"] for e in watcher.events)


def test_a_second_formation_on_the_same_agents_and_an_rc_leave(
    airborne: tuple[LocalFleet, str],
) -> None:
    """Two formations in a row on the same agents, the second by consensus; in it, an RC
    mode change the moment it forms. The followers are already in their slots then, so
    it forms at once and the change lands within the agent's pre-stream, before any
    guided heartbeat: the agent used to miss it and switch the pilot's LOITER back to
    GUIDED."""
    fleet, token = airborne
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(LEADER), 10, "the fleet")
        here = watcher.state(LEADER)
        too_fast = _request(LocalFrame(here["lat"], here["lon"]), speed_ms=9.0)
        assert api.post("/api/v1/formations", json=too_fast).status_code == 422  # audited
        first, _ = _start_formed(api, watcher, pause_s=30.0)
        # the spacing changes in flight; one that breaks the separation is refused
        wider = api.patch(f"/api/v1/formations/{first}", json={"spacing_m": 4.0})
        assert wider.status_code == 200, wider.text
        assert wider.json()["slots"][RIGHT]["y"] == pytest.approx(4.0 / math.sqrt(2.0))
        tight = api.patch(f"/api/v1/formations/{first}", json={"spacing_m": 1.0})
        assert tight.status_code == 422
        assert "minimum separation is 2 m" in tight.text
        watcher.wait_until(
            _formation_events(watcher, f"new slot in {first}"), 10, "the new slots told"
        )
        assert api.post(f"/api/v1/formations/{first}/stop").status_code == 200
        watcher.wait_until(
            lambda v: all((v[n].get("state") or {}).get("mode") == "BRAKE" for n in ALTITUDES),
            15,
            "every member holding",
        )

        # the second one by consensus: each follower's slot also from the other's state,
        # relayed by the hub; the followers form up on it
        second, _ = _start_formed(api, watcher, pause_s=30.0, spacing_m=4.0, controller="consensus")
        assert second != first
        assert api.get(f"/api/v1/formations/{second}").json()["controller"] == "consensus"
        watcher.wait_until(
            _formation_events(watcher, f"joined {second} (consensus)"), 10, "consensus joins"
        )
        try:
            # another GCS (or the RC switch) puts a follower in LOITER
            assert send_command(api, LEFT, name="set_mode", mode="LOITER")["status"] == ("accepted")
            watcher.wait_until(
                _formation_events(watcher, f"left {second}: the vehicle changed to LOITER"),
                10,
                "the follower leaving",
            )
            # it stays where the pilot put it: the agent sends no more targets nor modes
            deadline = time.monotonic() + 2.0
            watcher.wait_until(lambda v: time.monotonic() > deadline, 5, "two seconds")
            assert watcher.state(LEFT)["mode"] == "LOITER"
            # the others fly on in the second formation
            assert watcher.state(RIGHT)["mode"] == "GUIDED"
        finally:
            api.post(f"/api/v1/formations/{second}/stop")
        # leave the vehicles as the next test expects them: holding, in GUIDED's reach
        watcher.wait_until(
            lambda v: (v[RIGHT].get("state") or {}).get("mode") == "BRAKE",
            15,
            "the rest holding",
        )
        # who started, changed and stopped which formation, refusals included
        done = poll_until(
            lambda: _audited(api, first, second) or None, 10, "the formations audited"
        )
        assert ("formation.start", LEADER, "ok", first) in done
        assert ("formation.change", first, "ok", None) in done
        assert ("formation.change", first, "refused", None) in done
        assert ("formation.stop", second, "ok", None) in done
        assert ("formation.start", LEADER, "refused", None) in done


def _audited(api: httpx.Client, first: str, second: str) -> set[tuple[str, str, str, str | None]]:
    """The formation entries of the audit log, by the admin, once both stops are in."""
    found = set()
    for action in ("formation.start", "formation.change", "formation.stop"):
        for e in api.get("/api/v1/audit", params={"action": action}).json()["entries"]:
            assert e["actor"] == "admin"
            if action == "formation.change" and e["outcome"] == "refused":
                assert "minimum separation is 2 m" in e["detail"]["reason"], e
            found.add((action, e["target"], e["outcome"], e["detail"].get("formation_id")))
    stops = {t for a, t, *_ in found if a == "formation.stop"}
    return found if {first, second} <= stops else set()


def test_leader_flies_a_square_and_the_followers_keep_their_slots(
    airborne: tuple[LocalFleet, str],
) -> None:
    fleet, token = airborne
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(LEADER), 10, "the fleet")
        here = watcher.state(LEADER)
        frame = LocalFrame(here["lat"], here["lon"])
        answer = api.post("/api/v1/formations", json=_request(frame))
        assert answer.status_code == 200, answer.text
        formation = answer.json()
        try:
            _fly_and_measure(api, watcher, frame, formation)
        finally:
            api.post(f"/api/v1/formations/{formation['id']}/stop")
        watcher.wait_until(
            lambda v: all((v[n].get("state") or {}).get("mode") == "BRAKE" for n in ALTITUDES),
            15,
            "every member holding",
        )
        texts = [e["text"] for e in watcher.events if e.get("kind") == "formation"]
        assert any(t.startswith("left formation-") for t in texts), texts
        status = api.get(f"/api/v1/formations/{formation['id']}").json()
        assert status["stopped"] == "stopped by the operator"
        # the hub's own tracking figures: every leg measured, within the test's bound
        for follower in (RIGHT, LEFT):
            tracking = status["tracking"][follower]
            assert sorted(tracking["legs"]) == ["1", "2", "3", "4"], tracking
            assert all(leg["samples"] > 10 for leg in tracking["legs"].values()), tracking
            assert tracking["mission"]["rms_xy_m"] <= 0.6, tracking
            assert tracking["live_xy_m"] is not None
        # stored with the mission: who started and stopped it, and the same figures
        stored = next(
            f
            for f in api.get("/api/v1/formations").json()["formations"]
            if f["id"] == formation["id"]
        )
        assert (stored["started_by"], stored["stopped_by"]) == ("admin", "admin")
        assert stored["stop_reason"] == "stopped by the operator"
        assert stored["request"]["speed_ms"] == SPEED_MS
        for follower in (RIGHT, LEFT):
            kept = stored["tracking"][follower]["mission"]
            live = status["tracking"][follower]["mission"]
            assert kept["samples"] == live["samples"]
            assert kept["rms_xy_m"] == pytest.approx(live["rms_xy_m"], abs=1e-3)


def _fly_and_measure(
    api: httpx.Client, watcher: FleetWatcher, frame: LocalFrame, formation: dict[str, Any]
) -> None:
    # a member of a running formation cannot join another
    busy = api.post("/api/v1/formations", json=_request(frame))
    assert busy.status_code == 422
    assert "already in another formation" in busy.text

    # the followers join their slots, then the route's clock starts
    formed_at = poll_until(
        lambda: api.get(f"/api/v1/formations/{formation['id']}").json()["formed_at"],
        60,
        "the followers in their slots",
    )
    slots = {
        v: Offset(o["x"], o["y"], o["up"], OffsetFrame(o["frame"]))
        for v, o in formation["slots"].items()
    }
    route_frame = LocalFrame(*frame.to_geo(0.0, 0.0))
    corners = [(0.0, 0.0), (SIDE_M, 0.0), (SIDE_M, SIDE_M), (0.0, SIDE_M), (0.0, 0.0)]
    points = [(n, e, ALTITUDES[LEADER]) for n, e in corners]
    route = LeaderRoute(points, SPEED_MS, PAUSE_S)
    errors: dict[str, list[float]] = {RIGHT: [], LEFT: []}
    closest = math.inf

    def sample(vehicles: dict[str, Any]) -> bool:
        nonlocal closest
        now = time.time()
        states = {v: (vehicles.get(v) or {}).get("state") or {} for v in ALTITUDES}
        if any(s.get("lat") is None for s in states.values()):
            return False
        places = {v: _local(route_frame, s) for v, s in states.items()}
        pts = list(places.values())
        closest = min(
            [closest] + [math.dist(a, b) for i, a in enumerate(pts) for b in pts[i + 1 :]]
        )
        t = now - formed_at
        if route.leg_at(t) is not None:
            leader = states[LEADER]
            north, east, up = places[LEADER]
            state = LeaderState(
                north, east, up, leader["vn"], leader["ve"], 0.0,
                math.radians(leader["heading_deg"]), vehicles[LEADER]["last_seen"],
            )  # fmt: skip
            for follower in errors:
                # each vehicle's sample has its own time: the leader's is carried to
                # the follower's, so the figure is the tracking, not the sampling
                seen = vehicles[follower]["last_seen"]
                slot, _ = slot_target(state.predicted(seen), slots[follower])
                errors[follower].append(math.dist(slot[:2], places[follower][:2]))
        return t > route.duration_s

    flying = api.get(f"/api/v1/formations/{formation['id']}").json()
    assert flying["state"] == "flying"
    # the hub says when the route ends (a 1x fleet: the route's own seconds)
    assert flying["route_done_at"] == pytest.approx(formed_at + route.duration_s)
    watcher.wait_until(sample, route.duration_s + 30, "the square flown")
    poll_until(
        lambda: api.get(f"/api/v1/formations/{formation['id']}").json()["state"] == "route_done",
        5,
        "the hub to say the route is done",
    )
    rms = {f: math.sqrt(sum(e * e for e in es) / len(es)) for f, es in errors.items()}
    print(f"formation through the hub: RMS {rms}, closest pair {closest:.2f} m")
    assert all(len(es) > 50 for es in errors.values()), errors
    # The design's 0.5 m bar is held in the sped-up simulator (0.26 m there,
    # tests/simulator/test_formation_flight.py). Here the same flight measured 0.37-0.50 m
    # in eight runs (0.503 once, beside a benchmark) on the shared machine: the leader's
    # state travels agent -> hub -> agent at 10 Hz and the figure pairs 10 Hz reports, so
    # 0.6 m leaves room for load.
    assert max(rms.values()) <= 0.6, rms
    assert closest >= MIN_SEPARATION_M
