"""Scans through an in-process hub over real WebSockets: bad scans refused and counted with
the link alive, subscribers served, others not, and a stalled reader held to one scan."""

from __future__ import annotations

import contextlib
import io
import json
import math
import random
import re
import threading
import time
from array import array
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest
from plyfile import PlyData  # type: ignore[import-untyped]
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect

from backend.app import create_app
from protocol.messages import AGENT_WS_PATH, CLIENT_WS_PATH, Telemetry, VehicleState, encode
from protocol.scans import (
    MAX_BEAMS,
    ScanFrame,
    ScanPose,
    encode_scan,
    split_client_scan_frame,
)
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import access_token, api_client
from tests.support.hellos import agent_hello
from tests.support.hub_server import running_hub
from tests.support.waiting import poll_until

pytestmark = pytest.mark.integration

HOME = ScanPose(-35.363262, 149.165237, 587.0)


def scan(
    seq: int, *, beams: int = 720, at: float | None = None, metres: float = 5.0, noisy: bool = False
) -> bytes:
    """A scan of ``metres`` all round; quantised as it is, not as an agent would clean it.
    ``noisy`` adds a real sensor's millimetre noise: such ranges do not compress, so a
    stream of them fills a socket as a real LIDAR's does (constant ones deflate to bytes)."""
    noise = [random.randrange(-50, 50) if noisy else 0 for _ in range(beams)]
    ranges = array("H", [round(metres * 1000) + n for n in noise])
    return encode_scan(
        ScanFrame(
            seq=seq,
            sensor_time_us=seq * 100_000,
            utc_time=time.time() if at is None else at,
            duration_s=0.1,
            angle_min=0.0,
            angle_increment=-2 * math.pi / beams,
            range_max_m=12.0,
            pose_start=HOME,
            pose_end=HOME,
            ranges=ranges,
        )
    )


@contextlib.contextmanager
def agent(base: str, token: str, vehicle_id: str) -> Iterator[ClientConnection]:
    url = base.replace("http://", "ws://") + AGENT_WS_PATH
    with connect(url, additional_headers={"Authorization": f"Bearer {token}"}) as socket:
        socket.send(encode(agent_hello(vehicle_id, stream_id="s1")))
        assert json.loads(socket.recv(timeout=5))["type"] == "welcome"
        yield socket


@contextlib.contextmanager
def feed(base: str, token: str, **options: Any) -> Iterator[ClientConnection]:
    url = base.replace("http://", "ws://") + CLIENT_WS_PATH
    with contextlib.ExitStack() as stack:
        socket = stack.enter_context(
            connect(url, additional_headers={"Authorization": f"Bearer {token}"}, **options)
        )
        assert json.loads(socket.recv(timeout=5))["type"] == "fleet"
        yield socket
        with contextlib.suppress(ConnectionClosed, TimeoutError):
            stack.close()


def subscribe(socket: ClientConnection, vehicle_id: str) -> None:
    socket.send(json.dumps({"type": "subscribe_scans", "vehicle_id": vehicle_id}))
    while True:  # vehicle updates may come first
        answer = json.loads(socket.recv(timeout=5))
        if answer["type"] == "scan_subscriptions":
            assert vehicle_id in answer["vehicles"]
            return


def binary_frames(socket: ClientConnection, within_s: float) -> list[bytes]:
    frames, deadline = [], time.monotonic() + within_s
    while (remaining := deadline - time.monotonic()) > 0:
        try:
            frame = socket.recv(timeout=remaining)
        except TimeoutError:
            break
        if isinstance(frame, bytes):
            frames.append(frame)
    return frames


def binary_frames_until(
    socket: ClientConnection, enough: Callable[[list[bytes]], bool], timeout_s: float
) -> list[bytes]:
    """The binary frames read until ``enough`` says so; fails after ``timeout_s``."""
    frames: list[bytes] = []
    deadline = time.monotonic() + timeout_s
    while not enough(frames):
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            raise AssertionError(f"{len(frames)} binary frames in {timeout_s} s: too few")
        with contextlib.suppress(TimeoutError):
            frame = socket.recv(timeout=remaining)
            if isinstance(frame, bytes):
                frames.append(frame)
    return frames


def errors_to(socket: ClientConnection, within_s: float) -> list[str]:
    texts, deadline = [], time.monotonic() + within_s
    while (remaining := deadline - time.monotonic()) > 0:
        try:
            message = json.loads(socket.recv(timeout=remaining))
        except TimeoutError:
            break
        if message["type"] == "error":
            texts.append(message["message"])
    return texts


def test_bad_scans_are_refused_or_cleaned_counted_and_the_link_survives(
    hub: str, enrol: Callable[[str], str], admin_token: str
) -> None:
    with agent(hub, enrol("v1"), "v1") as socket, api_client(hub, admin_token) as api:
        good = scan(0)
        socket.send(good[:-2])  # a beam count the header disagrees with
        assert "beams: the header says 720 beams" in errors_to(socket, 2)[0]
        cases = [
            good[:24] + b"\0\0\0\0\0\0\xf8\x7f" + good[32:],  # utc_time NaN
            scan(1, at=time.time() + 3600),  # an hour ahead
            scan(2, at=time.time() - 30 * 86400),  # a month old
            scan(3, beams=MAX_BEAMS) + b"\0" * 4000,  # over the size limit
        ]
        for frame in cases:
            socket.send(frame)
        socket.send(scan(4, metres=40.0))  # beyond the sensor's 12 m: cleaned, not stored
        for seq in range(5, 40):  # a burst: more than 20 scans/s
            socket.send(scan(seq))
        socket.send(encode(Telemetry(seq=0, time=time.time(), state=VehicleState(alt_rel=3.0))))

        def counted() -> dict[str, Any] | None:
            body: dict[str, Any] = api.get("/api/v1/vehicles/v1/scans/diagnostics").json()
            return body if body["received"] == 41 and body["stored"] >= 1 else None

        diagnostics = poll_until(counted, 10, "every scan counted")
        assert diagnostics is not None
        assert diagnostics["rejected"]["bad_frame"] == 3
        assert diagnostics["rejected"]["time_future"] == 1
        assert diagnostics["rejected"]["time_past"] == 1
        assert diagnostics["rejected"]["rate"] >= 15
        assert diagnostics["cleaned_ranges"] == 720
        # The link survived all of it: the telemetry behind the bad scans is live.
        poll_until(
            lambda: (api.get("/api/v1/vehicles/v1").json()["state"] or {}).get("alt_rel") == 3.0,
            5,
            "the telemetry sent after the bad scans",
        )
        latest = api.get("/api/v1/vehicles/v1/scans/latest").json()
        assert latest["geodetic"]
        assert all(math.isfinite(v) for point in latest["enu"] for v in point)


def test_subscribers_get_scans_others_none_and_a_stalled_reader_holds_one(
    tmp_path: Path,
) -> None:
    settings = hub_settings(tmp_path, scan_max_rate_hz=100.0)
    app = create_app(settings)
    with running_hub(settings, app) as base:
        token = access_token(base, "admin", ADMIN_PASSWORD)
        with httpx.Client(base_url=base, headers={"Authorization": f"Bearer {token}"}) as api:
            tokens = {
                v: api.post(f"/api/v1/vehicles/{v}/agent-tokens").json()["token"]
                for v in ("v1", "v2")
            }
        with (
            # close_timeout: a feed that stopped reading with scans still coming cannot
            # finish the closing handshake; the default would wait 10 s for each.
            feed(base, token, close_timeout=1) as reader,
            feed(base, token) as bystander,
            # max_queue=1: the client library stops reading its socket once a frame waits.
            feed(base, token, max_queue=1, close_timeout=1) as stalled,
            agent(base, tokens["v1"], "v1") as v1,
            agent(base, tokens["v2"], "v2") as v2,
        ):
            subscribe(reader, "v1")
            feeds = app.state.hub.client_feeds
            reader_feed = next(f for f in feeds if f.scans.vehicles)
            subscribe(stalled, "v1")
            # Not the set's first subscribed feed: its order is arbitrary.
            stalled_feed = next(f for f in feeds if f.scans.vehicles and f is not reader_feed)
            # 16 KB scans at 100 Hz until the reader has had enough and the stalled
            # feed's socket is full: several MB, more than loopback's socket buffers.
            stop = threading.Event()

            def send(socket: ClientConnection) -> None:
                seq = 0
                while not stop.is_set():
                    socket.send(scan(seq, beams=MAX_BEAMS, noisy=True))
                    seq += 1
                    time.sleep(0.01)  # pacing the sender at the rate limit

            senders = [threading.Thread(target=send, args=(s,)) for s in (v1, v2)]
            for sender in senders:
                sender.start()
            try:
                # A count, not a window: a loaded machine delivers the same scans later.
                received = binary_frames_until(reader, lambda frames: len(frames) > 100, 120)
                poll_until(
                    lambda: stalled_feed.scans.replaced > 0, 120, "the stalled feed coalescing"
                )
                pending = stalled_feed.scans.pending
            finally:
                stop.set()
                for sender in senders:
                    sender.join(10)
            vehicles = {split_client_scan_frame(frame)[0] for frame in received}
            assert vehicles == {"v1"}  # v2's scans go to nobody: nobody asked
            assert len(received) > 100
            assert not binary_frames(bystander, 0.5)
            # The stalled feed: its socket is full, and the hub holds one newest scan for it.
            assert stalled_feed.scans.replaced > 0  # coalesced, not queued
            assert pending <= 1


def test_a_flights_world_points_export_as_ply(
    hub: str, enrol: Callable[[str], str], admin_token: str
) -> None:
    with agent(hub, enrol("v1"), "v1") as socket, api_client(hub, admin_token) as api:
        now = time.time()

        def telemetry(seq: int, armed: bool) -> str:
            state = VehicleState(armed=armed, alt_rel=2.0)
            return encode(Telemetry(seq=seq, time=now + seq, state=state))

        socket.send(telemetry(0, False))
        socket.send(telemetry(1, True))  # the flight starts
        for seq in range(5):
            socket.send(scan(seq, at=now + 1.5 + seq * 0.1))
        socket.send(telemetry(2, True))
        socket.send(telemetry(3, False))  # and ends

        def flight() -> list[dict[str, Any]]:
            listed = api.get("/api/v1/flights", params={"vehicle_id": "v1"}).json()["flights"]
            return [f for f in listed if f["end_time"] is not None]

        flight_id = poll_until(flight, 10, "the flight stored")[0]["id"]
        poll_until(
            lambda: api.get("/api/v1/vehicles/v1/scans/diagnostics").json()["stored"] == 5,
            10,
            "the scans stored",
        )
        answer = api.get(f"/api/v1/flights/{flight_id}/points.ply")
    assert answer.status_code == 200, answer.text
    ply = PlyData.read(io.BytesIO(answer.content))
    vertices = ply["vertex"]
    radius = np.hypot(vertices["x"], vertices["y"])
    assert len(radius) > 200  # 720 beams on a 5 m circle, downsampled to 10 cm voxels
    assert np.all(np.abs(radius - 5.0) < 0.1)


def test_an_obstacle_found_in_the_point_map_is_an_event_and_keeps_its_id(tmp_path: Path) -> None:
    # The site's origin 3 m below the drone: its scans' 5 m circle stands above the ground.
    origin = f"{HOME.lat},{HOME.lon},{HOME.alt_msl - 3.0}"
    settings = hub_settings(tmp_path, site_origin=origin, scan_obstacle_interval_s=0.2)
    with running_hub(settings) as base:
        token = access_token(base, "admin", ADMIN_PASSWORD)
        with api_client(base, token) as api:
            agent_token = api.post("/api/v1/vehicles/v1/agent-tokens").json()["token"]
            with feed(base, token) as dashboard, agent(base, agent_token, "v1") as socket:
                socket.send(scan(0))

                def obstacle_events() -> list[dict[str, Any]] | None:
                    found = []
                    with contextlib.suppress(TimeoutError):
                        while True:
                            message = json.loads(dashboard.recv(timeout=0.2))
                            if message["type"] == "events":
                                found += [e for e in message["events"] if e["kind"] == "obstacle"]
                    return found or None

                events = poll_until(obstacle_events, 10, "an obstacle event")
                assert events is not None
                assert events[0]["vehicle_id"] == "v1"
                # a 5 m circle around the drone, at its height
                assert re.match(
                    r"obstacle 1 found: 10\.\d m x 10\.\d m, up to 3\.\d m", events[0]["text"]
                )
                listed = api.get("/api/v1/scans/obstacles").json()
                assert [o["id"] for o in listed] == [1]
                socket.send(scan(1, at=time.time() + 0.1))  # seen again: the same obstacle
                poll_until(
                    lambda: api.get("/api/v1/vehicles/v1/scans/diagnostics").json()["live"] == 2,
                    10,
                    "the second scan",
                )
                assert [o["id"] for o in api.get("/api/v1/scans/obstacles").json()] == [1]


def _messages_of(socket: ClientConnection, kind: str, timeout_s: float) -> dict[str, Any]:
    """The first JSON message of this type (others are skipped); fails after the timeout."""
    deadline = time.monotonic() + timeout_s
    while (remaining := deadline - time.monotonic()) > 0:
        with contextlib.suppress(TimeoutError):
            frame = socket.recv(timeout=remaining)
            if isinstance(frame, str) and (message := json.loads(frame))["type"] == kind:
                return dict(message)
    raise AssertionError(f"no {kind} message within {timeout_s} s")


def test_map_subscribers_get_the_point_map_and_obstacles_others_none(tmp_path: Path) -> None:
    origin = f"{HOME.lat},{HOME.lon},{HOME.alt_msl - 3.0}"
    settings = hub_settings(tmp_path, site_origin=origin, scan_obstacle_interval_s=0.2)
    with running_hub(settings) as base:
        token = access_token(base, "admin", ADMIN_PASSWORD)
        with api_client(base, token) as api:
            agent_token = api.post("/api/v1/vehicles/v1/agent-tokens").json()["token"]
        with (
            feed(base, token) as mapper,
            feed(base, token) as bystander,
            agent(base, agent_token, "v1") as socket,
        ):
            mapper.send(json.dumps({"type": "subscribe_map", "layers": ["points", "obstacles"]}))
            answer = _messages_of(mapper, "map_subscriptions", 5)
            assert answer["layers"] == ["obstacles", "points"]
            # At once, what the map holds now: nothing yet.
            assert _messages_of(mapper, "point_map", 5)["map"]["voxels"] == 0
            assert _messages_of(mapper, "obstacles", 5)["obstacles"] == []

            socket.send(scan(0))  # a 5 m circle around the drone, 3 m above the site origin
            obstacles = _messages_of(mapper, "obstacles", 15)["obstacles"]
            assert [o["id"] for o in obstacles] == [1]
            assert len(obstacles[0]["outline"]) == 4
            points = _messages_of(mapper, "point_map", 15)["map"]
            assert points["site"]["lat"] == pytest.approx(HOME.lat)
            assert points["voxels"] == len(points["points"]) > 100
            # The circle's points are 5 m from the drone, 3 m up (10 cm voxels).
            ranges = [math.hypot(east, north) for east, north, _ in points["points"]]
            assert np.median(ranges) == pytest.approx(5.0, abs=0.1)

            # The map's layers never reach a feed that did not ask for them.
            seen = []
            with contextlib.suppress(TimeoutError):
                while True:
                    frame = bystander.recv(timeout=1.0)
                    if isinstance(frame, str):
                        seen.append(json.loads(frame)["type"])
            assert not {"point_map", "obstacles"} & set(seen), seen

            mapper.send(json.dumps({"type": "unsubscribe_map", "layers": ["points"]}))
            assert _messages_of(mapper, "map_subscriptions", 5)["layers"] == ["obstacles"]
