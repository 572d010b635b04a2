"""Test helpers that talk to real servers over real sockets."""

from __future__ import annotations

import asyncio
import json
import math
import os
import socket
import sqlite3
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import httpx
import uvicorn
from websockets.sync.client import ClientConnection, connect

from backend.app import create_app
from backend.settings import HubSettings
from gcs.launcher import FleetPlan, LocalFleet, end_with_parent, free_port
from protocol.messages import CLIENT_WS_PATH, PROTOCOL_VERSION, Hello
from tests.support.hubs import TEST_HUB_ENV, seed_database

T = TypeVar("T")

Vehicles = dict[str, dict[str, Any]]


class _NotifyingServer(uvicorn.Server):
    """A uvicorn server that signals once it is listening, so tests wait on an event."""

    def __init__(self, config: uvicorn.Config) -> None:
        super().__init__(config)
        self.listening = threading.Event()

    async def startup(self, sockets: Any = None) -> None:
        await super().startup(sockets)
        self.listening.set()


@contextmanager
def running_hub(settings: HubSettings, app: Any = None) -> Iterator[str]:
    """The hub app (``app``, else one made from ``settings``) served by uvicorn in a
    thread; yields its http:// base URL."""
    config = uvicorn.Config(
        app if app is not None else create_app(settings),
        host="127.0.0.1",
        port=settings.port,
        log_level="warning",
        ws_max_size=settings.max_frame_bytes,
        lifespan="on",
    )
    server = _NotifyingServer(config)
    thread = threading.Thread(target=lambda: asyncio.run(server.serve()), daemon=True)
    thread.start()
    if not server.listening.wait(20):
        raise RuntimeError("hub did not start listening within 20 s")
    try:
        yield f"http://127.0.0.1:{settings.port}"
    finally:
        server.should_exit = True
        thread.join(20)


class FleetWatcher:
    """Follows the hub's client WebSocket and waits for a state to appear."""

    def __init__(self, base_url: str, token: str) -> None:
        ws_url = base_url.replace("http://", "ws://") + CLIENT_WS_PATH
        self._stack = ExitStack()
        # max_queue=None: frames are taken off the socket as they come, whenever the
        # test reads them. With the default flow control, a watcher the test stopped
        # reading leaves the hub's closing frame behind unread updates, and closing it
        # waits out close_timeout (10 s) at the end of every such test.
        self._socket: ClientConnection = self._stack.enter_context(
            connect(ws_url, additional_headers={"Authorization": f"Bearer {token}"}, max_queue=None)
        )
        self.vehicles: dict[str, dict[str, Any]] = {}
        self.events: list[dict[str, Any]] = []  # every live event received, in order
        self.surveys: dict[str, dict[str, Any]] = {}  # the newest progress of each survey
        self.lease_holders: dict[str, str | None] = {}  # who flies each vehicle by hand
        self.dropped_events = 0

    def close(self) -> None:
        self._stack.close()

    def __enter__(self) -> FleetWatcher:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def wait_until(
        self, predicate: Callable[[dict[str, dict[str, Any]]], bool], timeout_s: float, what: str
    ) -> dict[str, dict[str, Any]]:
        deadline = time.monotonic() + timeout_s
        while not predicate(self.vehicles):
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise AssertionError(
                    f"timed out after {timeout_s} s waiting for {what}; "
                    f"last state: {json.dumps(self.vehicles)[:2000]}"
                )
            try:
                frame = self._socket.recv(timeout=remaining)
            except TimeoutError:
                continue
            message = json.loads(frame)
            if message["type"] == "fleet":
                self.vehicles = {vehicle["id"]: vehicle for vehicle in message["vehicles"]}
            elif message["type"] == "vehicles":
                # An update leaves out what it sent before (modes, ...): keep it.
                for vehicle in message["vehicles"]:
                    known = self.vehicles.get(vehicle["id"], {})
                    self.vehicles[vehicle["id"]] = {**known, **vehicle}
            elif message["type"] == "events":
                self.events += message["events"]
                self.dropped_events += message["dropped"]
            elif message["type"] == "survey":
                self.surveys[message["survey_id"]] = message
            elif message["type"] == "lease":
                self.lease_holders[message["vehicle_id"]] = message["holder"]
        return self.vehicles

    def state(self, vehicle_id: str) -> dict[str, Any]:
        return state_of(self.vehicles, vehicle_id)


# -- what a FleetWatcher waits for -----------------------------------------------------


def state_of(vehicles: Vehicles, vehicle: str) -> dict[str, Any]:
    """A vehicle's last state as the hub reported it; empty before the first."""
    return (vehicles.get(vehicle) or {}).get("state") or {}


def speed_of(state: dict[str, Any]) -> float:
    """Ground speed; unknown counts as moving fast, so "stopped" is never assumed."""
    speed = state.get("groundspeed")
    return math.inf if speed is None else float(speed)


def connected(vehicle: str) -> Callable[[Vehicles], bool]:
    """A predicate for `FleetWatcher.wait_until`: the vehicle's agent is connected."""
    return lambda vehicles: bool((vehicles.get(vehicle) or {}).get("connected"))


def ready(vehicle: str) -> Callable[[Vehicles], bool]:
    """A predicate for `FleetWatcher.wait_until`: connected, with a 3D fix, a home and
    a battery reading, so that a command has all it could check."""

    def check(vehicles: Vehicles) -> bool:
        state = state_of(vehicles, vehicle)
        return bool(
            connected(vehicle)(vehicles)
            and state.get("gps_fix", 0) >= 3
            and state.get("home_lat") is not None
            and state.get("battery_remaining") is not None
        )

    return check


def on_the_ground(vehicle: str) -> Callable[[Vehicles], bool]:
    """A predicate for `FleetWatcher.wait_until`: ready, disarmed, and on the ground as
    the autopilot itself says (``landed_state``), which is what the hub checks before a
    survey or a formation takes the vehicle. EXTENDED_SYS_STATE comes at 1 Hz, so for up
    to a second after the disarm the landed state still says "landing"."""

    def check(vehicles: Vehicles) -> bool:
        state = state_of(vehicles, vehicle)
        return bool(
            ready(vehicle)(vehicles)
            and state.get("armed") is False
            and state.get("landed_state") == "on_ground"
        )

    return check


def access_token(base_url: str, username: str, password: str) -> str:
    """A bearer token through the OAuth2 password flow, as an integration gets one."""
    response = httpx.post(
        f"{base_url}/api/v1/auth/token", data={"username": username, "password": password}
    )
    response.raise_for_status()
    token: str = response.json()["access_token"]
    return token


def api_client(base_url: str, token: str, timeout_s: float = 30) -> httpx.Client:
    return httpx.Client(
        base_url=base_url, timeout=timeout_s, headers={"Authorization": f"Bearer {token}"}
    )


def send_command(api: httpx.Client, vehicle: str, **command: Any) -> dict[str, Any]:
    """A command through the REST API, which must answer 200; returns its outcome."""
    response = api.post(f"/api/v1/vehicles/{vehicle}/commands", json=command)
    assert response.status_code == 200, response.text
    outcome: dict[str, Any] = response.json()["outcome"]
    return outcome


def take_off(
    api: httpx.Client, watcher: FleetWatcher, vehicle: str, altitude: float, *, above: float
) -> None:
    """GUIDED, armed and climbing to ``altitude``; back once it is higher than ``above``."""
    for command in ({"name": "set_mode", "mode": "GUIDED"}, {"name": "arm"}):
        assert send_command(api, vehicle, **command)["status"] == "accepted"
    assert send_command(api, vehicle, name="takeoff", altitude=altitude)["status"] == "accepted"
    watcher.wait_until(
        lambda v: (v[vehicle]["state"]["alt_rel"] or 0) > above, 60, f"{vehicle} climbing"
    )


# -- a shared fleet as a test may assume it -------------------------------------------

# Surveys that hold their drones: planned (checked, nothing uploaded) or flying.
ACTIVE_SURVEY_STATES = ("planned", "flying", "handover_offered")
# A pack below this cannot fly a survey's mission past the rails: say so, not a 422 later.
SETTLED_BATTERY_PCT = 40.0


def settle_fleet(
    base_url: str, token: str, vehicles: Sequence[str], timeout_s: float = 120
) -> None:
    """Bring a fleet that tests share to the state each may assume: no survey holding a
    drone, every vehicle connected, landed and disarmed (on the ground as its autopilot
    says), nobody flying one by hand, and a pack to fly on. A vehicle still armed or in
    the air is landed where it is; one already settled costs a look, nothing more."""
    with api_client(base_url, token) as api, FleetWatcher(base_url, token) as watcher:
        for survey in api.get("/api/v1/surveys").json()["surveys"]:
            if survey["state"] in ACTIVE_SURVEY_STATES:
                aborted = api.post(f"/api/v1/surveys/{survey['survey_id']}/abort")
                assert aborted.status_code == 200, aborted.text
        watcher.wait_until(
            lambda v: all(ready(vehicle)(v) for vehicle in vehicles),
            timeout_s,
            "the fleet connected and reporting",
        )
        up = [vehicle for vehicle in vehicles if not on_the_ground(vehicle)(watcher.vehicles)]
        if up:
            # Each vehicle's own answer is not checked: one may be landing already, and
            # the wait below is what counts.
            landing = {"vehicle_ids": up, "command": {"name": "land"}}
            answer = api.post("/api/v1/fleet/commands", json=landing)
            assert answer.status_code == 200, answer.text
        watcher.wait_until(
            lambda v: (
                all(on_the_ground(vehicle)(v) for vehicle in vehicles)
                and not any(watcher.lease_holders.get(vehicle) for vehicle in vehicles)
            ),
            timeout_s,
            f"{', '.join(vehicles)} landed and disarmed, with no lease held",
        )
        low = {
            vehicle: battery
            for vehicle in vehicles
            if (battery := watcher.state(vehicle)["battery_remaining"]) < SETTLED_BATTERY_PCT
        }
        assert not low, f"packs below {SETTLED_BATTERY_PCT:g} %, too low to fly on: {low}"


# -- processes -------------------------------------------------------------------------


@contextmanager
def running_fleet(data_dir: Path, **plan: Any) -> Iterator[LocalFleet]:
    """Hub, simulators and agents as real processes on loopback, started and ready;
    ``plan`` is what differs from `FleetPlan`'s defaults (vehicles, speedup, frames...).
    The hub starts on a copy of the migrated template database (its migration then finds
    nothing to do)."""
    seed_database(data_dir)
    with LocalFleet(FleetPlan(port=free_port(), data_dir=data_dir, **plan)) as fleet:
        fleet.start(TEST_HUB_ENV)
        fleet.wait_until_ready()
        yield fleet


@contextmanager
def agent_process(
    hub: str,
    token: str,
    vehicle_id: str,
    fcu_port: int,
    log_dir: Path | None = None,
    extra_args: Sequence[str] = (),
) -> Iterator[subprocess.Popen[bytes]]:
    """`gcs agent` as a process between a flight controller on loopback TCP at
    ``fcu_port`` and the hub
    at ``hub`` (its http:// URL), with ``extra_args`` added to its command line; its
    output goes to ``log_dir/<vehicle_id>.log`` if given, else where the test's goes."""
    with ExitStack() as stack:
        log = (
            None
            if log_dir is None
            else stack.enter_context((log_dir / f"{vehicle_id}.log").open("wb"))
        )
        agent = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "gcs",
                "agent",
                "--fcu",
                f"tcp:127.0.0.1:{fcu_port}",
                "--hub",
                hub.replace("http://", "ws://"),
                "--vehicle-id",
                vehicle_id,
                *extra_args,
            ],
            env={**os.environ, "GCS_AGENT_TOKEN": token},
            stdout=log,
            stderr=None if log is None else subprocess.STDOUT,
            preexec_fn=end_with_parent(),  # never outlives a killed pytest
        )
        try:
            yield agent
        finally:
            agent.terminate()
            agent.wait(10)


@dataclass(frozen=True)
class SpilledFrame:
    stream_id: str
    kind: str
    seq: int
    body: str


def spilled_frames(fleet: LocalFleet, vehicle: str) -> list[SpilledFrame]:
    """What the agent of a local fleet keeps on disk for the hub, oldest first (nothing
    before it first spills)."""
    path = fleet.plan.data_dir / "onboard" / vehicle / f"{vehicle}.outbox.sqlite"
    if not path.exists():
        return []
    with sqlite3.connect(path, timeout=5) as db:
        rows = db.execute("SELECT stream_id, kind, seq, body FROM frames ORDER BY id").fetchall()
    return [SpilledFrame(*row) for row in rows]


def poll_until(
    condition: Callable[[], T], timeout_s: float, what: str, *, every_s: float = 0.2
) -> T:
    """``condition()``'s first true value, for state that announces nothing (a file, a
    table, the hub's store behind its batching writer)."""
    deadline = time.monotonic() + timeout_s
    while not (value := condition()):
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s:.0f} s waiting for {what}")
        time.sleep(every_s)  # polling: there is no event to wait on
    return value


async def poll_until_async(
    condition: Callable[[], T], timeout_s: float, what: str, *, every_s: float = 0.05
) -> T:
    """`poll_until` inside an event loop: sleeps without blocking the loop, so the tasks
    under test run between looks."""
    deadline = time.monotonic() + timeout_s
    while not (value := condition()):
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s:g} s waiting for {what}")
        await asyncio.sleep(every_s)  # polling: there is no event to wait on
    return value


def agent_hello(
    vehicle_id: str = "v1",
    *,
    stream_id: str = "s",
    system_id: int = 1,
    modes: Sequence[str] = ("GUIDED", "LAND", "LOITER"),
) -> Hello:
    """The first message of an agent for an ArduPilot multirotor, for tests that play one."""
    return Hello(
        protocol=PROTOCOL_VERSION,
        vehicle_id=vehicle_id,
        autopilot="ardupilot",
        vehicle_type="multirotor",
        system_id=system_id,
        modes=list(modes),
        agent_version="test",
        stream_id=stream_id,
    )


def raw_http_answer(sock: socket.socket) -> str:
    """One HTTP/1.1 answer read off a raw socket, headers and body by its Content-Length,
    without waiting for the connection to close (the server may still be reading)."""
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = sock.recv(4096)
        if not chunk:
            break
        data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    length = next(
        (
            int(line.split(b":", 1)[1])
            for line in head.split(b"\r\n")
            if line.lower().startswith(b"content-length:")
        ),
        0,
    )
    while len(body) < length:
        chunk = sock.recv(4096)
        if not chunk:
            break
        body += chunk
    return (head + b"\r\n\r\n" + body).decode()
