"""The live orthomosaic end to end, on real processes: a hub, three simulators rendering
their camera's view of the synthetic ground, and three agents (posing, geotagging, queueing
and uploading the photos), flying a small survey at ten times real speed.

One flight makes both checks of the mosaic:

- one drone's link to the hub is cut mid-survey (a proxy between its agent and the hub):
  its photos wait on its disk and reach the hub once the link returns, and the mosaic
  completes (every photo taken is processed, none failed, the area covered);
- the ground targets (ArUco markers at known places) are found in the tiles the hub
  serves, at the median within one ground sample distance of where they lie, with the
  autopilots' exact poses. The same photos are then mosaicked again with GPS and attitude
  noise added to their poses (a drone without RTK), and that error is reported: printed,
  recorded as the test's properties (JUnit XML) and written to
  test-output/mosaic/flight-accuracy.txt.

Small photos (640 x 480) and a small area keep it short.
"""

from __future__ import annotations

import asyncio
import statistics
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import numpy.typing as npt
import pytest

from backend.imagery.mosaic.georef import TILE_PX, TMS
from backend.imagery.mosaic.photo import StoredPhoto
from backend.imagery.mosaic.service import MosaicService
from common.geodesy import LocalFrame
from common.opencv import cv2
from gcs.launcher import FleetPlan, LocalFleet, free_port
from protocol.photos import CameraIntrinsics, PhotoPose
from simulator.world.ground import Ground
from tests.mosaic_photos import NO_RTK, Noise, marker_errors_m, mosaic_of, target_errors_m
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.survey_shapes import geojson_area
from tests.support.tcp_proxy import CuttableProxy
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, on_the_ground

pytestmark = [pytest.mark.integration, pytest.mark.slow]

VEHICLES = ["sim_1", "sim_2", "sim_3"]
CUT = 1  # sim_2's link is the one cut
SPEEDUP = 10.0
CAMERA = CameraIntrinsics(
    sensor_width_mm=6.4,
    sensor_height_mm=4.8,
    image_width_px=640,
    image_height_px=480,
    focal_length_mm=4.8,
)
CAMERA_MODEL = "6.4,4.8,640,480,4.8"  # the agents' --camera-model: the same camera
ALTITUDE_M = 30.0
GSD_M = ALTITUDE_M * (CAMERA.sensor_width_mm / CAMERA.image_width_px) / CAMERA.focal_length_mm
# An area south of the homes holding nine of the ground's targets (a 30 m grid around home,
# 15 m in from the edges; Ground.around has none north-east of home).
WEST_M, SOUTH_M, WIDE_M, DEEP_M = -45.0, -95.0, 90.0, 90.0
SURVEY_S = 240  # the whole flight at ten times speed, on a shared machine
OUTPUT = Path(__file__).resolve().parents[2] / "test-output" / "mosaic"
QUEUED_WHILE_CUT = 2  # photos the cut drone must keep on its disk before the link returns


@dataclass
class Fleet:
    local: LocalFleet
    proxy: CuttableProxy
    token: str


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Fleet]:
    plan = FleetPlan(
        port=free_port(),
        data_dir=tmp_path_factory.mktemp("mosaic-flight"),
        vehicles=len(VEHICLES),
        speedup=SPEEDUP,
        camera_model=CAMERA_MODEL,
    )
    with LocalFleet(plan) as local, CuttableProxy(("127.0.0.1", plan.port)) as proxy:
        local.agent_hubs[CUT] = f"ws://127.0.0.1:{proxy.port}"
        local.start(
            hub_env={
                **TEST_HUB_ENV,
                # The cut lasts a few seconds: long enough for photos to queue, too short
                # for the survey to give the drone's lanes away.
                "GCS_SURVEY_LINK_TIMEOUT_S": "120",
                "GCS_SURVEY_UPDATE_INTERVAL_S": "0.2",
                "GCS_COMMANDS_PER_SECOND": "1000",
            }
        )
        local.wait_until_ready(timeout_s=60)
        token = access_token(plan.hub_http, "admin", plan.admin_password)
        yield Fleet(local, proxy, token)


def _request(plan: FleetPlan) -> dict[str, Any]:
    lat, lon, _ = plan.vehicle_home(0)
    frame = LocalFrame(lat, lon)
    corners = [
        (WEST_M, SOUTH_M),
        (WEST_M + WIDE_M, SOUTH_M),
        (WEST_M + WIDE_M, SOUTH_M + DEEP_M),
        (WEST_M, SOUTH_M + DEEP_M),
    ]
    return {
        "area": geojson_area(frame, corners),
        "camera": CAMERA.model_dump(),
        "altitude_m": ALTITUDE_M,
        "side_overlap_pct": 60,
        "front_overlap_pct": 70,
        "angle_deg": 0,
        "speed_ms": 5,
        "vehicle_ids": VEHICLES,
    }


def _get(api: httpx.Client, path: str) -> dict[str, Any]:
    answer = api.get(path)
    assert answer.status_code == 200, answer.text
    body: dict[str, Any] = answer.json()
    return body


def _mosaic(api: httpx.Client, survey_id: str) -> dict[str, Any] | None:
    answer = api.get(f"/api/v1/mosaics/{survey_id}")
    if answer.status_code == 404:
        return None
    assert answer.status_code == 200, answer.text
    body: dict[str, Any] = answer.json()
    return body


def _served_tiles(
    api: httpx.Client, mosaic: dict[str, Any]
) -> tuple[npt.NDArray[np.uint8], int, int, int]:
    """The native zoom's tiles as the hub serves them, laid side by side: the image, the
    global pixel column and row of its top-left corner, and the zoom."""
    zoom = int(mosaic["max_zoom"])
    west, south, east, north = mosaic["bounds"]
    tiles = list(TMS.tiles(west, south, east, north, [zoom]))
    x0, y0 = min(t.x for t in tiles), min(t.y for t in tiles)
    columns = max(t.x for t in tiles) - x0 + 1
    rows = max(t.y for t in tiles) - y0 + 1
    image = np.zeros((rows * TILE_PX, columns * TILE_PX, 3), np.uint8)
    served = 0
    for tile in tiles:
        answer = api.get(f"/api/v1/mosaics/{mosaic['survey_id']}/tiles/{zoom}/{tile.x}/{tile.y}")
        if answer.status_code == 404:  # inside the bounds' rectangle, outside the photos
            continue
        assert answer.status_code == 200, answer.text
        decoded = cv2.imdecode(np.frombuffer(answer.content, np.uint8), cv2.IMREAD_COLOR)
        top, left = (tile.y - y0) * TILE_PX, (tile.x - x0) * TILE_PX
        image[top : top + TILE_PX, left : left + TILE_PX] = decoded
        served += 1
    assert served > 0
    return image, x0 * TILE_PX, y0 * TILE_PX, zoom


def _noisy_errors(
    folder: Path, stored: list[dict[str, Any]], survey_id: str, ground: Ground, noise: Noise
) -> dict[int, float]:
    """The flown photos mosaicked again here, each pose moved by ``noise`` (the photos were
    rendered from the true pose, so this is what a drone reporting noisy poses would get)."""
    rng = np.random.default_rng(7)
    frame = ground.frame
    photos = []
    for row in stored:
        pose = PhotoPose.model_validate(row["pose"])
        east, north = frame.to_local(pose.lat, pose.lon)
        de, dn = rng.normal(0.0, noise.horizontal_m, 2)
        lat, lon = frame.to_geo(east + de, north + dn)
        droll, dpitch, dyaw = rng.normal(0.0, noise.attitude_deg, 3)
        noisy = pose.model_copy(
            update={
                "lat": lat,
                "lon": lon,
                "alt_rel": pose.alt_rel + float(rng.normal(0.0, noise.vertical_m)),
                "roll": pose.roll + float(droll),
                "pitch": pose.pitch + float(dpitch),
                "yaw": (pose.yaw + float(dyaw)) % 360.0,
            }
        )
        path = folder / "photos" / row["vehicle_id"] / f"{row['photo_id']}.jpg"
        photos.append(
            StoredPhoto(row["photo_id"], row["vehicle_id"], survey_id, path, noisy, CAMERA)
        )

    async def no_area(_: str) -> None:
        return None

    service = MosaicService(folder / "noisy-mosaic", no_area)
    asyncio.run(mosaic_of(service, photos))
    return target_errors_m(service, survey_id, ground)


def test_a_three_drone_survey_becomes_a_mosaic_true_to_its_targets_through_a_cut_link(
    fleet: Fleet, record_property: Any
) -> None:
    plan = fleet.local.plan
    cut_vid = VEHICLES[CUT]
    queue_dir = plan.data_dir / "onboard" / cut_vid / "photos"
    with (
        api_client(plan.hub_http, fleet.token) as api,
        FleetWatcher(plan.hub_http, fleet.token) as watcher,
    ):
        watcher.wait_until(
            lambda v: all(on_the_ground(vid)(v) for vid in VEHICLES),
            90,
            "three drones ready on the ground",
        )
        created = api.post("/api/v1/surveys", json=_request(plan))
        assert created.status_code == 201, created.text
        survey_id = str(created.json()["survey"]["id"])
        started = api.post(f"/api/v1/surveys/{survey_id}/start")
        assert started.status_code == 200, started.text

        # sim_2 has taken its first photo (the hub heard of it on the live link, the
        # fastest word of it): its link is cut, mid-survey.
        poll_until(
            lambda: (
                _get(api, f"/api/v1/surveys/{survey_id}/progress")["drones"][CUT]["photos"] >= 1
            ),
            SURVEY_S,
            f"{cut_vid}'s first photo",
            every_s=0.05,
        )
        fleet.proxy.cut()
        try:

            def waiting_for_the_hub() -> list[str] | None:
                # On the drone's disk and not at the hub. (A photo whose last chunk got in
                # just before the cut, its answer lost, is still on the disk but stored:
                # the agent learns so, and drops it, once the link returns.)
                on_disk = {p.stem for p in queue_dir.glob("*.jpg")}
                listed = _get(api, f"/api/v1/surveys/{survey_id}/photos")["photos"]
                missing = sorted(on_disk - {p["photo_id"] for p in listed})
                return missing if len(missing) >= QUEUED_WHILE_CUT else None

            queued = poll_until(
                waiting_for_the_hub,
                60,
                f"{QUEUED_WHILE_CUT} photos queued on {cut_vid}'s disk while cut off",
                every_s=0.1,
            )
            drone = _get(api, f"/api/v1/surveys/{survey_id}/progress")["drones"][CUT]
            assert drone["state"] == "flying", drone  # still surveying: mid-survey
        finally:
            fleet.proxy.start()

        done = poll_until(
            lambda: (
                (p := _get(api, f"/api/v1/surveys/{survey_id}/progress"))["state"]
                in ("done", "failed")
                and p
            ),
            SURVEY_S,
            "the survey to end",
        )
        assert done["state"] == "done", done
        assert [d["state"] for d in done["drones"]] == ["done"] * 3, done
        taken = done["photos"]
        assert all(d["photos"] > 0 for d in done["drones"]), done

        # Every photo the autopilots took reaches the mosaic, the queued ones included.
        mosaic = poll_until(
            lambda: (
                (m := _mosaic(api, survey_id)) is not None
                and m["processed"] + m["failed"] >= taken
                and m["pending"] == 0
                and m
            ),
            120,
            f"all {taken} photos processed into the mosaic",
        )
        assert mosaic["failed"] == 0, mosaic["failures"]
        assert mosaic["processed"] == taken
        assert mosaic["coverage_pct"] >= 99.0, mosaic["coverage_pct"]
        listed = _get(api, f"/api/v1/surveys/{survey_id}/photos")
        stored = listed["photos"]
        assert set(queued) <= {p["photo_id"] for p in stored}
        assert not list(queue_dir.glob("*.jpg")), "photos left on the drone's disk"

        image, left, top, zoom = _served_tiles(api, mosaic)

    ground = Ground.around(*plan.home, seed=1)  # the simulators' ground (photo_server.py)
    exact = marker_errors_m(image, left, top, zoom, ground)
    inside = {t.marker_id for t in ground.targets if _in_area(plan, t.lat, t.lon)}
    # The same targets as the served tiles' (which stop at the area's edge).
    noisy = {
        marker: error
        for marker, error in _noisy_errors(plan.data_dir, stored, survey_id, ground, NO_RTK).items()
        if marker in inside
    }
    exact_cm = statistics.median(exact.values()) * 100
    report = (
        f"ground targets in the flown mosaic (GSD {GSD_M * 100:.2f} cm, {taken} photos, "
        f"{len(queued)} queued while cut off, {mosaic['coverage_pct']:.1f} % covered): "
        f"exact poses {len(exact)} found, median error {exact_cm:.2f} cm; "
        f"with noise (GPS {NO_RTK.horizontal_m} m h / {NO_RTK.vertical_m} m v, attitude "
        f"{NO_RTK.attitude_deg} deg, 1 sigma) {len(noisy)} found, median error "
        f"{statistics.median(noisy.values()) * 100 if noisy else float('nan'):.2f} cm"
    )
    print(report)
    # Kept where the browser tests keep their screenshots, as the run's record.
    OUTPUT.mkdir(parents=True, exist_ok=True)
    (OUTPUT / "flight-accuracy.txt").write_text(report + "\n")
    record_property("mosaic_exact_median_error_m", statistics.median(exact.values()))
    record_property(
        "mosaic_noisy_median_error_m", statistics.median(noisy.values()) if noisy else None
    )
    assert len(inside) == 9
    assert len(exact) >= len(inside) - 1, (sorted(exact), sorted(inside))
    assert statistics.median(exact.values()) <= GSD_M, report


def _in_area(plan: FleetPlan, lat: float, lon: float) -> bool:
    lat0, lon0, _ = plan.vehicle_home(0)
    east, north = LocalFrame(lat0, lon0).to_local(lat, lon)
    return WEST_M < east < WEST_M + WIDE_M and SOUTH_M < north < SOUTH_M + DEEP_M
