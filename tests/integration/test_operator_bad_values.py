"""An operator's out-of-range number never reaches, let alone ends, a vehicle's agent.

Against real processes (the session's fleet: hub, simulators, agents), an operator sends
1e300, -1e300, NaN and Infinity in every number of every route that ends up in a MAVLink
field: each command with a number, to one vehicle and to a group (take-off, go-to,
speed, set home, parameter set, mission upload, set current), the parameter route, the
mission routes, and stick input on the dashboard's socket. Each one is refused naming
the field (a 422 on REST, an error reply on the socket); afterwards the agent is still
running, still connected, and still carries a good command there and back (and the
vehicle's parameter is unchanged).
"""

from __future__ import annotations

import json
import math
import secrets
import time
from collections.abc import Callable
from typing import Annotated, Any, get_args, get_origin

import httpx
import pytest
from pydantic import BaseModel
from websockets.sync.client import ClientConnection, connect

from gcs.launcher import LocalFleet
from protocol.messages import CLIENT_WS_PATH, Command, ManualAxes, MissionItem
from tests.support.api import access_token, api_client
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, connected

pytestmark = pytest.mark.integration

VEHICLE = "sim_1"
# What a careless or hostile client can put on the wire: json.dumps spells NaN and
# Infinity as JavaScript does (httpx's json= refuses to), and a number in a string is
# read as that number by a lax parser.
BAD: list[float | str] = [1e300, -1e300, math.nan, math.inf, "1e300", "NaN"]
BAD_IDS = ["1e300", "-1e300", "NaN", "Infinity", "string 1e300", "string NaN"]
WAYPOINT = {"command": 16, "lat": -35.3632, "lon": 149.1652, "alt": 20.0}
# Every number a mission item carries into MISSION_ITEM_INT
ITEM_FIELDS = ("param1", "param2", "param3", "param4", "lat", "lon", "alt", "command", "frame")
STICK = {"x": 0, "y": 0, "z": 500, "r": 0, "buttons": 0}


def _commands(bad: float | str) -> list[tuple[str, dict[str, Any]]]:
    """Each command with ``bad`` in one of its numbers, with the field a 422 must name:
    every number of every command the protocol has (the others carry none)."""
    home = {"name": "set_home", "use_current": False, "lat": -35.36, "lon": 149.16}
    goto = {"name": "goto", "lat": -35.36, "lon": 149.16, "altitude": 10}
    commands: list[tuple[str, dict[str, Any]]] = [
        ("altitude", {"name": "takeoff", "altitude": bad}),
        ("lat", {**goto, "lat": bad}),
        ("lon", {**goto, "lon": bad}),
        ("altitude", {**goto, "altitude": bad}),
        ("speed", {"name": "change_speed", "speed": bad}),
        ("lat", {**home, "alt_msl": 500.0, "lat": bad}),
        ("lon", {**home, "alt_msl": 500.0, "lon": bad}),
        ("alt_msl", {**home, "alt_msl": bad}),
        ("value", {"name": "param_set", "param": "WPNAV_SPEED", "value": bad}),
        ("seq", {"name": "mission_set_current", "seq": bad}),
    ]
    for field in ITEM_FIELDS:
        items = [WAYPOINT, {**WAYPOINT, field: bad}]
        commands.append((field, {"name": "mission_upload", "items": items}))
    return commands


def _types(annotation: Any) -> set[Any]:
    """The plain types an annotation admits, through unions and ``Annotated`` (the strict
    ``Number`` is one, and ``Number | None`` holds one)."""
    args = get_args(annotation)
    if get_origin(annotation) is Annotated:
        return _types(args[0])
    return set().union(*(_types(arg) for arg in args)) if args else {annotation}


def _numbers(model: type[BaseModel]) -> set[str]:
    """The fields of ``model`` that hold a number (a bool is not one)."""
    return {
        name
        for name, field in model.model_fields.items()
        if {int, float} & _types(field.annotation)
    }


def test_the_cases_cover_every_number_of_every_command() -> None:
    """A number added to a command (or a command added) must join the cases below."""
    covered: set[tuple[str, str]] = set()
    for field, command in _commands(1e300):
        covered.add((command["name"], field))
    expected = {
        (model.model_fields["name"].default, field)
        for model in get_args(get_args(Command)[0])
        for field in _numbers(model)
    }
    expected |= {("mission_upload", field) for field in _numbers(MissionItem)}
    assert covered == expected
    assert set(ITEM_FIELDS) == _numbers(MissionItem)
    assert set(STICK) == _numbers(ManualAxes)


Request = Callable[[httpx.Client], httpx.Response]


def _send(method: str, url: str, body: object) -> Request:
    content = json.dumps(body)
    headers = {"content-type": "application/json"}
    return lambda api: api.request(method, url, content=content, headers=headers)


def _requests(bad: float | str) -> list[tuple[str, Request]]:
    """(the field a 422 must name, the request) for every REST route that reaches MAVLink."""
    base = f"/api/v1/vehicles/{VEHICLE}"
    requests: list[tuple[str, Request]] = []
    for field, command in _commands(bad):
        requests.append((field, _send("POST", f"{base}/commands", command)))
        group = {"vehicle_ids": [VEHICLE], "command": command}
        requests.append((field, _send("POST", "/api/v1/fleet/commands", group)))
    requests.append(("value", _send("PUT", f"{base}/params/WPNAV_SPEED", {"value": bad})))
    for field in ITEM_FIELDS:
        body = {"items": [WAYPOINT, {**WAYPOINT, field: bad}]}
        requests.append((field, _send("POST", f"{base}/mission", body)))
    requests.append(("seq", _send("PUT", f"{base}/mission/current", {"seq": bad})))
    return requests


@pytest.fixture
def one_vehicle(settled_fleet: LocalFleet) -> LocalFleet:
    """The session's fleet, of which these tests use VEHICLE alone: what they send is
    refused before it reaches the agent, and what does reach it (a parameter read, the
    same value written back, a lease taken and given back) leaves the vehicle as it was,
    so no fleet of their own is needed (one took 10-20 s to start)."""
    return settled_fleet


@pytest.fixture(scope="module")
def operator(fleet: LocalFleet) -> str:
    """An operator's bearer token: the role that may command, below the admin."""
    base = fleet.plan.hub_http
    admin = access_token(base, "admin", fleet.plan.admin_password)
    password = secrets.token_urlsafe(18)
    with api_client(base, admin) as api:
        created = api.post(
            "/api/v1/users", json={"username": "op", "password": password, "role": "operator"}
        )
        assert created.status_code == 201, created.text
    return access_token(base, "op", password)


def _past_the_budget(call: Callable[[], httpx.Response], what: str) -> httpx.Response:
    """``call``'s answer once the vehicle's budget allows it: the routes before spent
    this second's (each bad value is still a request that counts), and a 429 says when
    to ask again."""

    def allowed() -> httpx.Response | None:
        answer = call()
        return None if answer.status_code == 429 else answer

    answer = poll_until(allowed, 10, f"the vehicle budget to allow {what}")
    assert answer is not None
    return answer


def _wpnav_speed(api: httpx.Client) -> float:
    read = _past_the_budget(
        lambda: api.get(f"/api/v1/vehicles/{VEHICLE}/params/WPNAV_SPEED"), "a read"
    )
    assert read.status_code == 200, read.text
    value: float = read.json()["values"]["WPNAV_SPEED"]
    return value


def _still_answering(fleet: LocalFleet, api: httpx.Client, wpnav_speed: float) -> None:
    fleet.check_alive()  # raises if the agent (or anything else) exited
    with FleetWatcher(fleet.plan.hub_http, api.headers["Authorization"][7:]) as watcher:
        watcher.wait_until(connected(VEHICLE), 30, f"{VEHICLE} connected")
    assert _wpnav_speed(api) == wpnav_speed, "nothing reached the vehicle"
    # a write the vehicle echoes: the agent still carries a command there and back
    good = _past_the_budget(
        lambda: api.put(
            f"/api/v1/vehicles/{VEHICLE}/params/WPNAV_SPEED", json={"value": wpnav_speed}
        ),
        "a write",
    )
    assert good.status_code == 200, good.text


@pytest.mark.parametrize("bad", BAD, ids=BAD_IDS)
def test_every_rest_route_refuses_the_number_naming_the_field(
    one_vehicle: LocalFleet, operator: str, bad: float | str
) -> None:
    with api_client(one_vehicle.plan.hub_http, operator) as api:
        with FleetWatcher(one_vehicle.plan.hub_http, operator) as watcher:
            watcher.wait_until(connected(VEHICLE), 30, f"{VEHICLE} connected")
        wpnav_speed = _wpnav_speed(api)
        for field, request in _requests(bad):
            response = request(api)
            assert response.status_code == 422, (field, response.text)
            named = [error["loc"][-1] for error in response.json()["detail"]]
            assert field in named, (field, response.text)
        _still_answering(one_vehicle, api, wpnav_speed)


def _said(socket: ClientConnection, *kinds: str, timeout_s: float = 30) -> dict[str, Any]:
    """The next message of one of these kinds (fleet states and events in between are
    read past: they keep coming, so the wait has a deadline of its own)."""
    deadline = time.monotonic() + timeout_s
    while (remaining := deadline - time.monotonic()) > 0:
        try:
            message: dict[str, Any] = json.loads(socket.recv(timeout=remaining))
        except TimeoutError:
            break
        if message["type"] in kinds:
            return message
    raise AssertionError(f"no {' or '.join(kinds)} message within {timeout_s} s")


def test_stick_input_refuses_the_number_naming_the_axis(
    one_vehicle: LocalFleet, operator: str
) -> None:
    """Stick input is the one path to MAVLink (MANUAL_CONTROL, int16 and uint16 fields)
    that is not REST: the lease holder's socket gets an error naming the axis, and the
    socket, the lease and the agent go on."""
    base = one_vehicle.plan.hub_http
    url = base.replace("http://", "ws://") + CLIENT_WS_PATH
    with (
        api_client(base, operator) as api,
        connect(url, additional_headers={"Authorization": f"Bearer {operator}"}) as pilot,
    ):
        with FleetWatcher(base, operator) as watcher:
            watcher.wait_until(connected(VEHICLE), 30, f"{VEHICLE} connected")
        # The lease opens only once the agent has checked that the autopilot takes
        # MANUAL_CONTROL from it: ArduPilot from its GCS's id, which the launcher set to
        # the agent's 254 (the deployer's guide's setup), as `gcs demo` does.
        wpnav_speed = _wpnav_speed(api)
        pilot.send(json.dumps({"type": "control", "vehicle_id": VEHICLE, "action": "acquire"}))
        granted = _said(pilot, "lease", "lease_refused")  # a refusal: say which
        assert granted["type"] == "lease", granted
        assert granted["holder"] == "op", granted
        seq = 0
        # fewer than the 20 bad frames after which the hub closes a socket
        for bad in (1e300, math.nan, -math.inf):
            for axis in STICK:
                seq += 1
                frame = {
                    "type": "manual",
                    "vehicle_id": VEHICLE,
                    "seq": seq,
                    "axes": {**STICK, axis: bad},
                }
                pilot.send(json.dumps(frame))
                error = _said(pilot, "error")
                assert error["code"] == "invalid_message", (bad, axis, error)
                assert f"manual.axes.{axis}:" in error["message"], (bad, axis, error)
        pilot.send(json.dumps({"type": "ping", "nonce": "still here"}))
        assert _said(pilot, "pong")["nonce"] == "still here"
        pilot.send(json.dumps({"type": "control", "vehicle_id": VEHICLE, "action": "release"}))
        assert _said(pilot, "lease")["holder"] is None
        _still_answering(one_vehicle, api, wpnav_speed)
