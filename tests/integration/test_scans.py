"""LIDAR scans end to end: a simulated drone's LIDAR (the YDLIDAR bytes over TCP), the
agent's parser and clock, the binary frames to the hub, the store, the world points, and
the subscribers. Real processes on loopback, the simulator at real time (the LIDAR's
arrival times are the agent's to measure)."""

from __future__ import annotations

import math
import sqlite3
import threading
import time
from collections.abc import Iterator
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest
from websockets.sync.client import ClientConnection, connect

from backend.scans.points import world_points
from common.geodesy import LocalFrame
from gcs.launcher import LocalFleet
from protocol.messages import CLIENT_WS_PATH
from protocol.scans import ScanFrame, split_client_scan_frame
from simulator.world.obstacles import default_scene
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.processes import running_fleet
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher

pytestmark = [pytest.mark.integration, pytest.mark.slow]

ALTITUDE_M = 3.0
WORLD = default_scene()


@pytest.fixture(scope="module")
def lidar_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    with running_fleet(
        tmp_path_factory.mktemp("lidar"), vehicles=1, speedup=1.0, lidars=True
    ) as fleet:
        yield fleet


@pytest.fixture(scope="module")
def token(lidar_fleet: LocalFleet) -> str:
    return access_token(lidar_fleet.plan.hub_http, "admin", lidar_fleet.plan.admin_password)


class ScanFeed:
    """A dashboard's live feed, collecting the scans it receives (binary frames)."""

    def __init__(self, base: str, token: str) -> None:
        self._stack = ExitStack()
        self.socket: ClientConnection = self._stack.enter_context(
            connect(
                base.replace("http://", "ws://") + CLIENT_WS_PATH,
                additional_headers={"Authorization": f"Bearer {token}"},
            )
        )
        self.scans: list[tuple[str, ScanFrame]] = []
        self.texts: list[str] = []
        self._lock = threading.Lock()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        try:
            for frame in self.socket:
                with self._lock:
                    if isinstance(frame, bytes):
                        self.scans.append(split_client_scan_frame(frame))
                    else:
                        self.texts.append(frame)
        except Exception:  # the socket closed at the end of the test
            return

    def send(self, text: str) -> None:
        self.socket.send(text)

    def taken(self) -> list[ScanFrame]:
        with self._lock:
            return [frame for _, frame in self.scans]

    def close(self) -> None:
        self._stack.close()
        self._reader.join(5)


def _site(fleet: LocalFleet) -> LocalFrame:
    return LocalFrame(*fleet.plan.vehicle_home(0))


def _surface_error(enu: np.ndarray) -> np.ndarray:
    """Distance to the nearest surface: an obstacle's side, or the ground (a beam tilted
    down as the drone pitches to accelerate meets it)."""
    error: np.ndarray = np.minimum(WORLD.distance_to_surface(enu), np.abs(enu[:, 2]))
    return error


def _errors(frames: list[ScanFrame], site: LocalFrame) -> np.ndarray:
    return np.concatenate([_surface_error(world_points(f, site).enu) for f in frames])


def _speed(frame: ScanFrame, site: LocalFrame) -> float:
    a, b = frame.pose_start, frame.pose_end
    start, end = site.to_enu(a.lat, a.lon, a.alt_msl), site.to_enu(b.lat, b.lon, b.alt_msl)
    return math.dist(start[:2], end[:2]) / frame.duration_s


def _turned(frame: ScanFrame) -> float:
    turn = frame.pose_end.yaw - frame.pose_start.yaw
    return abs((turn + math.pi) % (2 * math.pi) - math.pi)


def _command(api: httpx.Client, vehicle: str, **command: Any) -> None:
    answer = api.post(f"/api/v1/vehicles/{vehicle}/commands", json=command, timeout=30)
    assert answer.status_code == 200, answer.text
    assert answer.json()["outcome"]["status"] == "accepted", answer.text


def test_world_points_lie_on_the_obstacles_hovering_yawing_and_moving(
    lidar_fleet: LocalFleet, token: str
) -> None:
    base, vehicle, site = lidar_fleet.plan.hub_http, lidar_fleet.vehicle_id(0), _site(lidar_fleet)
    feed, idle = ScanFeed(base, token), ScanFeed(base, token)
    try:
        with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
            watcher.wait_until(
                lambda v: bool((v.get(vehicle, {}).get("state") or {}).get("ready_to_fly")),
                60,
                "the vehicle ready to fly",
            )
            _command(api, vehicle, name="set_mode", mode="GUIDED")
            _command(api, vehicle, name="arm")
            _command(api, vehicle, name="takeoff", altitude=ALTITUDE_M)
            watcher.wait_until(
                lambda v: (v[vehicle]["state"].get("alt_rel") or 0) > ALTITUDE_M - 0.1,
                30,
                "the take-off",
            )
            feed.send(f'{{"type": "subscribe_scans", "vehicle_id": "{vehicle}"}}')
            poll_until(lambda: len(feed.taken()) >= 20, 20, "20 scans while hovering")
            hovering = feed.taken()
            errors = _errors(hovering, site)
            assert np.median(errors) <= 0.05, np.median(errors)
            assert np.mean(errors <= 0.20) >= 0.99, np.percentile(errors, 99)

            # The hub's own world points, in WGS-84, of its latest scan.
            latest = api.get(f"/api/v1/vehicles/{vehicle}/scans/latest").json()
            hub_enu = np.array([site.to_enu(*p) for p in latest["geodetic"]])
            hub_errors = _surface_error(hub_enu)
            assert len(hub_errors) > 300
            assert np.median(hub_errors) <= 0.05

            # Fly west, then back east at 3 m/s: the turn to face the travel is a yaw
            # under way, and each turn of the head is 30 cm of travel.
            _command(api, vehicle, name="change_speed", speed=3.0)
            west = site.to_geo(-6.0, -3.0)
            _command(api, vehicle, name="goto", lat=west[0], lon=west[1], altitude=ALTITUDE_M)
            poll_until(
                lambda: (
                    _speed(feed.taken()[-1], site) < 0.1
                    and abs(
                        site.to_local(feed.taken()[-1].pose_end.lat, feed.taken()[-1].pose_end.lon)[
                            0
                        ]
                        + 6.0
                    )
                    < 0.3
                ),
                30,
                "arrival in the west",
            )
            before = len(feed.taken())
            east = site.to_geo(8.0, -3.0)
            _command(api, vehicle, name="goto", lat=east[0], lon=east[1], altitude=ALTITUDE_M)
            poll_until(
                lambda: any(_speed(f, site) > 2.8 for f in feed.taken()[before:]), 20, "3 m/s"
            )
            poll_until(lambda: _speed(feed.taken()[-1], site) < 0.5, 20, "arrival in the east")
            flight = feed.taken()[before:]
            moving = [f for f in flight if _speed(f, site) > 2.5]
            yawing = [f for f in flight if _turned(f) > math.radians(3.0)]
            assert len(moving) >= 5
            assert yawing, "the vehicle turned to face its travel"
            for frames in (moving, yawing):
                errors = _errors(frames, site)
                assert np.median(errors) <= 0.05, np.median(errors)
                assert np.mean(errors <= 0.20) >= 0.99, np.percentile(errors, 99)

            # Every scan is stored: the moving ones are in the hub's store too.
            start, end = moving[0].utc_time - 0.01, moving[-1].utc_time + 0.01

            def stored_page() -> dict[str, Any] | None:
                page: dict[str, Any] = api.get(
                    f"/api/v1/vehicles/{vehicle}/scans",
                    params={"start": start, "end": end, "limit": 100},
                ).json()
                return page if len(page["scans"]) >= len(moving) else None

            page = poll_until(stored_page, 10, "the moving scans in the store")
            assert page is not None
            stored = np.array([site.to_enu(*p) for scan in page["scans"] for p in scan["geodetic"]])
            assert np.median(_surface_error(stored)) <= 0.05
            _command(api, vehicle, name="land")
        # A dashboard that did not subscribe received no scan.
        assert not idle.scans
        diagnostics = httpx.get(
            f"{base}/api/v1/vehicles/{vehicle}/scans/diagnostics",
            headers={"Authorization": f"Bearer {token}"},
        ).json()
        assert diagnostics["rejected"] == {}
        assert diagnostics["live"] >= len(feed.taken())
    finally:
        feed.close()
        idle.close()


OUTAGE_S = 30.0


def _stored(fleet: LocalFleet, query: str) -> list[tuple[Any, ...]]:
    """The hub's SQLite store itself: the ground truth, not an API's view of it."""
    with sqlite3.connect(fleet.plan.data_dir / "gcs.sqlite3", timeout=10) as db:
        return db.execute(query).fetchall()


def test_after_a_30_s_hub_outage_the_scans_in_the_budget_arrive_and_telemetry_is_whole(
    tmp_path: Path,
) -> None:
    with running_fleet(tmp_path, vehicles=1, speedup=1.0, lidars=True) as fleet:
        vehicle = fleet.vehicle_id(0)
        count = f"SELECT count(*) FROM scans WHERE vehicle_id = '{vehicle}'"
        poll_until(lambda: _stored(fleet, count)[0][0] >= 20, 60, "scans stored")
        went = time.time()
        fleet.kill("hub")
        time.sleep(OUTAGE_S)  # the outage itself, not a wait for anything
        back = time.time()
        fleet.start_hub(TEST_HUB_ENV)
        fleet.wait_until_ready()

        within = (
            f"SELECT count(*) FROM scans WHERE vehicle_id = '{vehicle}' "
            f"AND time >= {went + 1.0} AND time <= {back - 1.0}"
        )
        expected = 0.95 * 10.0 * (back - went - 2.0)  # 10 Hz, less the edges
        poll_until(
            lambda: _stored(fleet, within)[0][0] >= expected,
            60,
            f"{expected:.0f} scans from the outage in the store",
        )
        # ...and they were stored as replayed, while telemetry lost nothing.
        token = access_token(fleet.plan.hub_http, "admin", fleet.plan.admin_password)
        with api_client(fleet.plan.hub_http, token) as api:
            diagnostics = api.get(f"/api/v1/vehicles/{vehicle}/scans/diagnostics").json()
        assert diagnostics["replayed"] >= expected
        assert diagnostics["rejected"] == {}
        query = f"SELECT seq FROM telemetry WHERE vehicle_id = '{vehicle}'"

        def whole() -> list[int] | None:
            seqs = sorted(seq for (seq,) in _stored(fleet, query))
            late = [t for (t,) in _stored(fleet, "SELECT max(time) FROM telemetry")]
            covered = late and late[0] is not None and late[0] >= back
            return seqs if covered and seqs == list(range(len(seqs))) else None

        poll_until(whole, 60, "telemetry through the outage, every sample once")
