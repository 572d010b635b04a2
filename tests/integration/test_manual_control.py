"""Flying by hand through the hub: the lease, the 25 Hz stream, the agent's deadman.

Real hub, simulator and agent processes on loopback, the simulator at real time so that
the agent's 0.5 s deadman (wall clock) is 0.5 s of simulated flight.
"""

from __future__ import annotations

import json
import math
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from websockets.sync.client import ClientConnection, connect

from gcs.launcher import LocalFleet
from protocol.messages import CLIENT_WS_PATH
from tests.helpers import (
    FleetWatcher,
    access_token,
    api_client,
    poll_until,
    ready,
    running_fleet,
    send_command,
)

pytestmark = pytest.mark.integration

VEHICLE = "sim_1"
RATE_HZ = 25.0


class Pilot:
    """A dashboard's socket that flies: sends frames, keeps what the hub says back."""

    def __init__(self, base_url: str, token: str) -> None:
        url = base_url.replace("http://", "ws://") + CLIENT_WS_PATH
        self.socket: ClientConnection = connect(
            url, additional_headers={"Authorization": f"Bearer {token}"}
        )
        self.received: list[dict[str, Any]] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        self.seq = 0
        self.last_sent_at = 0.0

    def _read(self) -> None:
        try:
            for frame in self.socket:
                self.received.append(json.loads(frame))
        except Exception:
            return

    def said(self, kind: str) -> list[dict[str, Any]]:
        return [message for message in list(self.received) if message["type"] == kind]

    def control(self, action: str) -> None:
        self.socket.send(json.dumps({"type": "control", "vehicle_id": VEHICLE, "action": action}))

    def stick(self, x: int, y: int = 0, z: int = 500, r: int = 0) -> None:
        self.seq += 1
        axes = {"x": x, "y": y, "z": z, "r": r}
        self.socket.send(
            json.dumps({"type": "manual", "vehicle_id": VEHICLE, "seq": self.seq, "axes": axes})
        )

    def stream(self, stop: threading.Event, x: int, z: int = 500) -> None:
        """Frames at RATE_HZ until ``stop``, paced on the monotonic clock (the pacing is
        the test's input, not a wait on the system under test)."""
        period = 1.0 / RATE_HZ
        next_at = time.monotonic()
        while not stop.is_set():
            self.stick(x, z=z)
            self.last_sent_at = time.monotonic()
            next_at += period
            stop.wait(max(0.0, next_at - time.monotonic()))

    def close(self) -> None:
        self.socket.close()
        self._reader.join(5)


@pytest.fixture(scope="module")
def flying(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[LocalFleet, str]]:
    """One copter at 10 m in GUIDED, ArduPilot's SYSID_MYGCS set to the agent's 254."""
    data_dir: Path = tmp_path_factory.mktemp("manual")
    with running_fleet(data_dir, vehicles=1, speedup=1.0) as fleet:
        base = fleet.plan.hub_http
        token = access_token(base, "admin", fleet.plan.admin_password)
        with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
            watcher.wait_until(ready(VEHICLE), 60, f"{VEHICLE} ready")
            mygcs = api.put(f"/api/v1/vehicles/{VEHICLE}/params/SYSID_MYGCS", json={"value": 254})
            assert mygcs.status_code == 200, mygcs.text
            take_off(api, watcher)
        yield fleet, token


def take_off(api: httpx.Client, watcher: FleetWatcher) -> None:
    assert send_command(api, VEHICLE, name="set_mode", mode="GUIDED")["status"] == "accepted"
    assert send_command(api, VEHICLE, name="arm")["status"] == "accepted"
    assert send_command(api, VEHICLE, name="takeoff", altitude=10.0)["status"] == "accepted"
    watcher.wait_until(
        lambda v: (v[VEHICLE]["state"]["alt_rel"] or 0) >= 9.0, 60, f"{VEHICLE} at 10 m"
    )


def metres_moved(before: dict[str, Any], after: dict[str, Any]) -> tuple[float, float]:
    """North and east metres between two states (flat earth: a few tens of metres)."""
    north = (after["lat"] - before["lat"]) * 111_320.0
    east = (after["lon"] - before["lon"]) * 111_320.0 * math.cos(math.radians(before["lat"]))
    return north, east


def test_input_without_the_lease_is_refused(flying: tuple[LocalFleet, str]) -> None:
    fleet, token = flying
    pilot = Pilot(fleet.plan.hub_http, token)
    try:
        pilot.stick(1000)
        refusal = poll_until(lambda: pilot.said("error"), 5, "the hub's refusal")[0]
        assert refusal["code"] == "forbidden"
        assert "does not hold the manual-control lease" in refusal["message"]
    finally:
        pilot.close()


def test_sticks_fly_the_vehicle_and_silence_holds_it(flying: tuple[LocalFleet, str]) -> None:
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher:
        watcher.wait_until(ready(VEHICLE), 10, "the fleet")
        pilot = Pilot(base, token)
        try:
            pilot.control("acquire")
            lease = poll_until(lambda: pilot.said("lease"), 5, "the lease")[-1]
            assert lease["holder"] == "admin"
            before = dict(watcher.state(VEHICLE))
            heading = math.radians(before["heading_deg"])

            stop = threading.Event()
            streamer = threading.Thread(target=pilot.stream, args=(stop, 600), daemon=True)
            streamer.start()  # 60 % forward at 25 Hz
            try:
                after = watcher.wait_until(
                    lambda v: math.hypot(*metres_moved(before, v[VEHICLE]["state"])) > 8.0,
                    10,
                    f"{VEHICLE} to fly on the sticks",
                )[VEHICLE]["state"]
                assert after["mode"] == "LOITER"  # the agent switched to the pilot mode
            finally:
                stop.set()
                streamer.join(5)
            stopped_at = time.monotonic()
            north, east = metres_moved(before, after)
            moved = math.hypot(north, east)
            # Forward: along the heading the vehicle had when the sticks moved.
            along = north * math.cos(heading) + east * math.sin(heading)
            assert along > 0.9 * moved, (north, east, before["heading_deg"])

            # The stream stops: the agent's deadman holds the vehicle.
            held = watcher.wait_until(
                lambda v: v[VEHICLE]["state"]["mode"] == "BRAKE", 5, "the deadman's BRAKE"
            )
            assert held
            events = [e for e in watcher.events if e["kind"] == "manual" and "stopped" in e["text"]]
            if not events:
                watcher.wait_until(
                    lambda v: any(e["kind"] == "manual" for e in watcher.events), 5, "the event"
                )
                events = [e for e in watcher.events if "stopped" in e["text"]]
            silence = float(events[-1]["text"].split("stopped for ")[1].split(" s")[0])
            assert 0.5 <= silence <= 0.6, events[-1]["text"]
            # And the hub ended the lease, so the stream cannot take it back unasked.
            poll_until(
                lambda: [m for m in pilot.said("lease") if m["holder"] is None],
                5,
                "the lease to end",
            )
            assert time.monotonic() - stopped_at < 5
        finally:
            pilot.close()


def test_a_mode_change_the_agent_did_not_make_ends_the_lease(
    flying: tuple[LocalFleet, str],
) -> None:
    """The RC pilot's mode switch outranks the browser; here the change comes from
    another ground station's set_mode, which the agent can no more tell apart from the
    transmitter than ArduPilot's HEARTBEAT lets it."""
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(VEHICLE), 10, "the fleet")
        pilot = Pilot(base, token)
        stop = threading.Event()
        streamer = threading.Thread(target=pilot.stream, args=(stop, 0), daemon=True)
        try:
            pilot.control("acquire")
            poll_until(lambda: [m for m in pilot.said("lease") if m["holder"]], 5, "the lease")
            streamer.start()
            watcher.wait_until(
                lambda v: v[VEHICLE]["state"]["mode"] == "LOITER", 5, "the pilot mode"
            )
            switched = send_command(api, VEHICLE, name="set_mode", mode="RTL")
            assert switched["status"] == "accepted"
            ended = poll_until(
                lambda: [m for m in pilot.said("lease") if m["holder"] is None],
                5,
                "the lease to end",
            )[-1]
            assert "changed to RTL" in ended["reason"]
            # Frames still streaming are now refused at the hub, never forwarded.
            poll_until(
                lambda: [m for m in pilot.said("error") if "lease" in m["message"]],
                5,
                "the refusal of the stream",
            )
            # The stream still running did not take the vehicle back into LOITER.
            watcher.wait_until(lambda v: v[VEHICLE]["state"]["mode"] == "RTL", 5, "RTL")
        finally:
            stop.set()
            if streamer.is_alive():
                streamer.join(5)
            pilot.close()
