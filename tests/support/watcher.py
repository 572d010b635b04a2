"""Following the hub's client WebSocket (`FleetWatcher`) and the predicates it waits for."""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from contextlib import ExitStack
from typing import Any

from websockets.sync.client import ClientConnection, connect

from protocol.messages import CLIENT_WS_PATH

Vehicles = dict[str, dict[str, Any]]


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
