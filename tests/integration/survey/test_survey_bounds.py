"""Survey planning and area imports are bounded, over the real hub on loopback:

- a plan is estimated from the area and the camera first, and one over the hub's limits
  is refused at once with a 422 naming the estimate and the limit's setting; the hub goes
  on answering meanwhile (a 4.4 km square at 1 m took a hub to 13.7 GB);
- a drone's mission longer than its store is a 422 naming it, never a 500;
- a plan whose client goes away stops (the planner is cooperative: /metrics counts it);
- importing an area file needs the planning permission, is bounded in size and vertices,
  and is rate-limited per user.
"""

from __future__ import annotations

import re
import socket
import threading
import time
import uuid
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import httpx
import pytest

from common.geodesy import LocalFrame
from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client, raw_http_answer
from tests.support.survey_shapes import kml_polygon
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready

pytestmark = pytest.mark.integration

VEHICLES = ["sim_1", "sim_2", "sim_3"]
PASSWORD = "correct horse battery"


@pytest.fixture
def api(fleet: LocalFleet, fleet_admin_token: str) -> Iterator[httpx.Client]:
    with api_client(fleet.plan.hub_http, fleet_admin_token, timeout_s=120) as client:
        yield client


@pytest.fixture
def watcher(fleet: LocalFleet, fleet_admin_token: str) -> Iterator[FleetWatcher]:
    with FleetWatcher(fleet.plan.hub_http, fleet_admin_token) as watching:
        for vehicle in VEHICLES:
            watching.wait_until(ready(vehicle), 60, f"{vehicle} ready")
        yield watching


def _square(state: dict[str, Any], side_m: float, **changes: Any) -> dict[str, Any]:
    """A survey of a square `side_m` across, 50 m north-east of the vehicle."""
    frame = LocalFrame(state["lat"], state["lon"], 0.0)
    corners = [(50, 50), (50 + side_m, 50), (50 + side_m, 50 + side_m), (50, 50 + side_m)]
    ring = [[lon, lat] for lat, lon in (frame.to_geo(x, y) for x, y in corners)]
    body: dict[str, Any] = {
        "area": {"type": "Polygon", "coordinates": [[*ring, ring[0]]]},
        "camera": "sony_a6000_16mm",
        "altitude_m": 40,
        "vehicle_ids": VEHICLES,
    }
    body.update(changes)
    return body


class HealthProbe:
    """/health round trips, every 50 ms on a thread of its own, while the test runs."""

    def __init__(self, base_url: str) -> None:
        self._url = f"{base_url}/api/v1/health"
        self._stop = threading.Event()
        self.round_trips: list[float] = []  # of answers 200 (others are in `failed`)
        self.failed: list[int] = []
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        with httpx.Client(timeout=30) as client:
            while not self._stop.is_set():
                started = time.monotonic()
                status = client.get(self._url).status_code
                if status == 200:
                    self.round_trips.append(time.monotonic() - started)
                else:
                    self.failed.append(status)
                self._stop.wait(0.05)

    def __enter__(self) -> HealthProbe:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(30)


def test_a_huge_area_at_one_metre_is_refused_at_once_naming_the_limit(
    fleet: LocalFleet, api: httpx.Client, watcher: FleetWatcher
) -> None:
    body = _square(watcher.state("sim_1"), 4400, altitude_m=1)
    with HealthProbe(fleet.plan.hub_http) as probe, ThreadPoolExecutor(8) as pool:
        poll_until(lambda: len(probe.round_trips) >= 1, 10, "/health answering")
        started = time.monotonic()
        answers = list(
            pool.map(lambda _: api.post("/api/v1/surveys/preview", json=body), range(40))
        )
        elapsed = time.monotonic() - started
        poll_until(lambda: len(probe.round_trips) >= 5, 10, "/health answering after")
    for answer in answers:
        assert answer.status_code == 422, answer.text[:500]
        # The estimate and the limit's setting: 4.4 km x 4.4 km over 0.44 x 0.2 m a photo.
        assert re.search(
            r"about 224,\d{3},\d{3} photos; the limit is [\d,]+ \(survey_max_photos\)",
            answer.text,
        ), answer.text
        assert "(survey_max_lanes)" in answer.text
    assert elapsed < 10, f"40 refusals took {elapsed:.1f} s"
    assert not probe.failed
    assert max(probe.round_trips) < 1.0, probe.round_trips


def test_creating_a_huge_survey_is_refused_the_same_way(
    settled_fleet: LocalFleet, api: httpx.Client, watcher: FleetWatcher
) -> None:
    body = _square(watcher.state("sim_1"), 4400, altitude_m=1)
    started = time.monotonic()
    answer = api.post("/api/v1/surveys", json=body)
    assert answer.status_code == 422, answer.text[:500]
    assert "(survey_max_photos)" in answer.text
    assert time.monotonic() - started < 5


def test_a_small_square_flown_low_is_a_422_never_a_500(
    api: httpx.Client, watcher: FleetWatcher
) -> None:
    state = watcher.state("sim_1")
    # At 1 m: refused from the estimate, before any planning.
    answer = api.post("/api/v1/surveys/preview", json=_square(state, 200, altitude_m=1))
    assert answer.status_code == 422, answer.text[:500]
    assert "(survey_max_photos)" in answer.text
    # One drone at 3.5 m with no front overlap: few enough photos, but 130 lanes, 783
    # items: over a vehicle's mission store, from the estimate.
    answer = api.post(
        "/api/v1/surveys/preview",
        json=_square(state, 200, altitude_m=3.5, front_overlap_pct=0, vehicle_ids=["sim_1"]),
    )
    assert answer.status_code == 422, answer.text[:500]
    assert "about 783 mission items for a drone; the limit is 700" in answer.text
    # Two drones, 150 m at 2.5 m: the estimate counts on the lanes being shared out, but
    # the split shares out each lane and both fly all 137 (825 items): the exact count,
    # after planning, refuses it.
    answer = api.post(
        "/api/v1/surveys/preview",
        json=_square(
            state, 150, altitude_m=2.5, front_overlap_pct=0, angle_deg=0, vehicle_ids=VEHICLES[:2]
        ),
    )
    assert answer.status_code == 422, answer.text[:500]
    assert re.search(r"sim_1 8\d\d", answer.text), answer.text
    assert "the limit is 700 (survey_max_mission_items)" in answer.text


def _metric(base_url: str, token: str, series: str) -> float:
    text = httpx.get(f"{base_url}/metrics", headers={"Authorization": f"Bearer {token}"}).text
    match = re.search(rf"^{re.escape(series)} (\S+)$", text, re.MULTILINE)
    assert match, f"{series} is not in /metrics"
    return float(match.group(1))


def test_a_plan_whose_client_goes_away_stops(
    fleet: LocalFleet, fleet_admin_token: str, watcher: FleetWatcher
) -> None:
    base, token = fleet.plan.hub_http, fleet_admin_token
    stopped = 'gcs_survey_plans_stopped_total{reason="disconnect"}'
    before = _metric(base, token, stopped)
    # Within every limit (18,656 photos, 549 items a drone) but seconds of work: the
    # three drones' split plans each part many times over.
    body = httpx.Request(
        "POST", "http://x", json=_square(watcher.state("sim_1"), 200, altitude_m=5)
    ).content
    port = int(base.rsplit(":", 1)[1])
    with socket.create_connection(("127.0.0.1", port)) as raw:
        raw.sendall(
            b"POST /api/v1/surveys/preview HTTP/1.1\r\nHost: 127.0.0.1\r\n"
            + f"Authorization: Bearer {token}\r\nContent-Type: application/json\r\n".encode()
            + f"Content-Length: {len(body)}\r\n\r\n".encode()
            + body
        )
        poll_until(
            lambda: _metric(base, token, "gcs_survey_plans_running") >= 1, 10, "the plan running"
        )
    gone = time.monotonic()  # the client has closed its connection
    poll_until(lambda: _metric(base, token, stopped) > before, 10, "the plan stopped")
    assert time.monotonic() - gone < 3
    poll_until(lambda: _metric(base, token, "gcs_survey_plans_running") == 0, 5, "no plan")


# -- area imports (a hub of its own: its rate limits start afresh) ---------------------------


def _user(admin_api: httpx.Client, hub: str, role: str) -> str:
    name = f"{role}-{uuid.uuid4().hex[:6]}"
    created = admin_api.post(
        "/api/v1/users", json={"username": name, "password": PASSWORD, "role": role}
    )
    assert created.status_code == 201, created.text
    return access_token(hub, name, PASSWORD)


GEOJSON = '{"type": "Polygon", "coordinates": [[[8, 47], [8.01, 47], [8.01, 47.01], [8, 47]]]}'


def test_importing_an_area_needs_the_planning_permission(hub: str, admin_api: httpx.Client) -> None:
    file = {"format": "geojson", "content": GEOJSON}
    with api_client(hub, _user(admin_api, hub, "viewer")) as viewer:
        refused = viewer.post("/api/v1/surveys/import", json=file)
    assert refused.status_code == 403, refused.text
    with api_client(hub, _user(admin_api, hub, "operator")) as operator:
        assert operator.post("/api/v1/surveys/import", json=file).status_code == 200


def test_an_oversized_area_file_is_refused_naming_the_limit(
    hub: str, admin_api: httpx.Client
) -> None:
    with api_client(hub, _user(admin_api, hub, "operator")) as operator:
        big = operator.post(
            "/api/v1/surveys/import",
            json={"format": "geojson", "content": GEOJSON + " " * 1_000_000},
        )
        assert big.status_code == 413, big.text[:500]
        assert "the limit is 1,000,000 (survey_import_max_bytes)" in big.text
        # 45,000 vertices in 900 kB: under the size limit, over the vertices'.
        many = operator.post(
            "/api/v1/surveys/import", json={"format": "kml", "content": kml_polygon(45_000)}
        )
        assert many.status_code == 422, many.text[:500]
        assert "45,000 vertices; the limit is 10,000 (survey_import_max_vertices)" in many.text


def test_area_imports_are_rate_limited_per_user(hub: str, admin_api: httpx.Client) -> None:
    file = {"format": "geojson", "content": GEOJSON}
    with api_client(hub, _user(admin_api, hub, "operator")) as operator:
        for _ in range(10):  # survey_imports_per_minute
            assert operator.post("/api/v1/surveys/import", json=file).status_code == 200
        refused = operator.post("/api/v1/surveys/import", json=file)
        assert refused.status_code == 429, refused.text
        assert 1 <= int(refused.headers["Retry-After"]) <= 60
    with api_client(hub, _user(admin_api, hub, "operator")) as another:  # a budget of its own
        assert another.post("/api/v1/surveys/import", json=file).status_code == 200


def test_an_import_over_its_rate_is_refused_before_its_body_is_read(
    hub: str, admin_api: httpx.Client
) -> None:
    """A user importing in a loop: once over the rate, each request is answered from its
    headers, its (up to a megabyte of) body never read or decoded on the event loop.
    Here the body never even comes: the refusal must not wait for it."""
    file = {"format": "geojson", "content": GEOJSON}
    token = _user(admin_api, hub, "operator")
    with api_client(hub, token) as operator:
        for _ in range(10):  # survey_imports_per_minute
            assert operator.post("/api/v1/surveys/import", json=file).status_code == 200
    host, port = hub.removeprefix("http://").split(":")
    with socket.create_connection((host, int(port)), timeout=5) as raw:
        raw.sendall(
            b"POST /api/v1/surveys/import HTTP/1.1\r\nHost: x\r\n"
            + f"Authorization: Bearer {token}\r\n".encode()
            + b"Content-Type: application/json\r\nContent-Length: 900000\r\n\r\n{"
        )
        answer = raw_http_answer(raw)  # within the 5 s timeout; the body never comes
    assert answer.startswith("HTTP/1.1 429"), answer
    assert "retry-after:" in answer.lower()
    assert "survey imports" in answer
