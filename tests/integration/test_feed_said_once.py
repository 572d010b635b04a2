"""The live feed sends what an agent says once (modes, autopilot, vehicle type) once per
client connection, and again only when it changes: not in every 10 Hz vehicle frame."""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect

from protocol.messages import (
    AGENT_WS_PATH,
    CLIENT_WS_PATH,
    ModeList,
    Telemetry,
    VehicleState,
    encode,
)
from tests.support.hellos import agent_hello

SAID_ONCE = ("autopilot", "vehicle_type", "modes")
COPTER_MODES = ("STABILIZE", "ALT_HOLD", "LOITER", "GUIDED", "LAND", "RTL", "AUTO")


@contextmanager
def _socket(base_url: str, path: str, token: str) -> Iterator[ClientConnection]:
    url = base_url.replace("http://", "ws://") + path
    with connect(url, additional_headers={"Authorization": f"Bearer {token}"}) as socket:
        try:
            yield socket
        finally:
            with contextlib.suppress(ConnectionClosed):
                socket.close()


@contextmanager
def _agent(base_url: str, token: str, modes: tuple[str, ...]) -> Iterator[ClientConnection]:
    with _socket(base_url, AGENT_WS_PATH, token) as socket:
        socket.send(encode(agent_hello("v1", stream_id=f"run-{len(modes)}", modes=modes)))
        assert json.loads(socket.recv(timeout=5))["type"] == "welcome"
        yield socket


def _send_telemetry(agent: ClientConnection, count: int) -> None:
    for seq in range(count):
        state = VehicleState(alt_rel=float(seq))
        agent.send(encode(Telemetry(seq=seq, time=time.time(), state=state)))


def _vehicle_frames(
    client: ClientConnection, done: Callable[[dict[str, Any]], bool], timeout_s: float = 10
) -> list[dict[str, Any]]:
    """The client's vehicle updates up to and including the first that is ``done``."""
    frames: list[dict[str, Any]] = []
    deadline = time.monotonic() + timeout_s
    while not frames or not done(frames[-1]):
        remaining = deadline - time.monotonic()
        assert remaining > 0, f"no final update in {timeout_s} s; got {frames}"
        message = json.loads(client.recv(timeout=remaining))
        if message["type"] == "vehicles":
            frames += message["vehicles"]
    return frames


def _alt(vehicle: dict[str, Any]) -> float | None:
    return (vehicle.get("state") or {}).get("alt_rel")


def test_modes_go_once_per_feed_and_again_when_they_change(
    hub: str, enrol: Callable[[str], str], admin_token: str
) -> None:
    token = enrol("v1")
    with _socket(hub, CLIENT_WS_PATH, admin_token) as first:
        assert json.loads(first.recv(timeout=5)) == {"type": "fleet", "vehicles": []}
        with _agent(hub, token, COPTER_MODES) as agent:
            _send_telemetry(agent, 20)
            frames = _vehicle_frames(first, lambda vehicle: _alt(vehicle) == 19.0)
            # The first frame names the vehicle's modes; no later one repeats them.
            assert frames[0]["modes"] == list(COPTER_MODES)
            assert (frames[0]["autopilot"], frames[0]["vehicle_type"]) == (
                "ardupilot",
                "multirotor",
            )
            assert len(frames) >= 2
            for later in frames[1:]:
                assert not set(SAID_ONCE) & set(later), later

            # A reconnecting client gets them again, in its snapshot.
            with _socket(hub, CLIENT_WS_PATH, admin_token) as second:
                snapshot = json.loads(second.recv(timeout=5))
                assert snapshot["type"] == "fleet"
                assert snapshot["vehicles"][0]["modes"] == list(COPTER_MODES)
                agent.send(
                    encode(Telemetry(seq=20, time=time.time(), state=VehicleState(alt_rel=20)))
                )
                frames = _vehicle_frames(second, lambda vehicle: _alt(vehicle) == 20.0)
                assert all(not set(SAID_ONCE) & set(frame) for frame in frames), frames
        _vehicle_frames(first, lambda vehicle: vehicle["connected"] is False)

        # The agent comes back with other modes (another firmware): the feed sends them.
        fewer = ("GUIDED", "LAND")
        with _agent(hub, token, fewer) as agent:
            _send_telemetry(agent, 1)
            frames = _vehicle_frames(first, lambda vehicle: vehicle.get("modes") is not None)
            assert frames[-1]["modes"] == list(fewer)


def test_the_autopilots_own_mode_list_replaces_the_hellos(
    hub: str, enrol: Callable[[str], str], admin_token: str, admin_api: Any
) -> None:
    """An agent says the modes the autopilot listed (AVAILABLE_MODES) after its hello: the
    feed sends them once, the REST API lists them, and set_mode is checked against them."""
    token = enrol("v1")
    with _socket(hub, CLIENT_WS_PATH, admin_token) as client:
        assert json.loads(client.recv(timeout=5))["type"] == "fleet"
        with _agent(hub, token, COPTER_MODES) as agent:
            _send_telemetry(agent, 1)
            first = _vehicle_frames(client, lambda vehicle: vehicle.get("modes") is not None)
            assert first[-1]["modes"] == list(COPTER_MODES)
            listed = ("STABILIZE", "LOITER", "SMART_RTL", "AUTO_RTL")
            agent.send(encode(ModeList(modes=list(listed))))
            frames = _vehicle_frames(client, lambda vehicle: vehicle.get("modes") is not None)
            assert frames[-1]["modes"] == list(listed)
            assert admin_api.get("/api/v1/vehicles/v1").json()["modes"] == list(listed)
            dropped = admin_api.post(
                "/api/v1/vehicles/v1/commands", json={"name": "set_mode", "mode": "GUIDED"}
            )
            assert dropped.status_code == 422, dropped.text
            assert "it has: STABILIZE, LOITER, SMART_RTL, AUTO_RTL" in dropped.text
