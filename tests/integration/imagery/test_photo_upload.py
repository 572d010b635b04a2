"""Photos from a simulated vehicle's camera to the hub, with real processes: the
simulator (its camera endpoint rendering the synthetic ground), the agent (posing,
geotagging, queueing, uploading), and a hub behind a TCP proxy that cuts the agent's link.

The camera is fired by DO_DIGICAM_CONTROL, as a mission's camera command would; the
vehicle stays on the ground, over a ground laid 30 m below it.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import pytest
from PIL import ExifTags, Image
from pymavlink import mavutil

from gcs.launcher import free_port
from simulator.config import DEFAULT_HOME
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub
from tests.support.photos import CAMERA_MODEL, GROUND_BELOW_M, _accepts
from tests.support.processes import agent_process
from tests.support.tcp_proxy import CuttableProxy
from tests.support.waiting import poll_until

pytestmark = pytest.mark.integration

VEHICLE = "cam_1"


@dataclass
class CameraVehicle:
    api: httpx.Client
    hub_dir: Path
    photo_dir: Path
    proxy: CuttableProxy
    fcu: Any  # a pymavlink connection to the simulator, as a second GCS

    def fire(self) -> None:
        self.fcu.mav.command_long_send(
            1, 1, mavutil.mavlink.MAV_CMD_DO_DIGICAM_CONTROL, 0, 0, 0, 0, 0, 1, 0, 0
        )

    def photos(self) -> dict[str, Any]:
        answer = self.api.get(f"/api/v1/vehicles/{VEHICLE}/photos", params={"limit": 1000})
        assert answer.status_code == 200, answer.text
        body: dict[str, Any] = answer.json()
        return body


@pytest.fixture(scope="module")
def vehicle(tmp_path_factory: pytest.TempPathFactory) -> Iterator[CameraVehicle]:
    hub_dir = tmp_path_factory.mktemp("hub")
    logs = tmp_path_factory.mktemp("logs")
    photo_dir = tmp_path_factory.mktemp("onboard") / "photos"
    sim_port, camera_port = free_port(), free_port()
    lat, lon, alt = DEFAULT_HOME.lat, DEFAULT_HOME.lon, DEFAULT_HOME.alt
    with (
        running_hub(hub_settings(hub_dir)) as hub,
        api_client(hub, access_token(hub, "admin", ADMIN_PASSWORD)) as api,
        (logs / "sim.log").open("wb") as sim_log,
    ):
        enrolled = api.post(f"/api/v1/vehicles/{VEHICLE}/agent-tokens")
        assert enrolled.status_code == 201, enrolled.text
        sim = subprocess.Popen(
            [
                *(sys.executable, "-m", "gcs", "sim"),
                *("--listen", f"tcp:127.0.0.1:{sim_port}"),
                *("--camera", f"tcp:127.0.0.1:{camera_port}"),
                f"--ground={lat},{lon},{alt - GROUND_BELOW_M}",
            ],
            stdout=sim_log,
            stderr=subprocess.STDOUT,
        )
        hub_port = int(hub.rsplit(":", 1)[1])
        try:
            with (
                CuttableProxy(("127.0.0.1", hub_port)) as proxy,
                agent_process(
                    f"http://127.0.0.1:{proxy.port}",
                    enrolled.json()["token"],
                    VEHICLE,
                    sim_port,
                    logs,
                    extra_args=[
                        *("--camera", f"sim+http://127.0.0.1:{camera_port}"),
                        *("--camera-model", CAMERA_MODEL),
                        *("--photo-dir", str(photo_dir)),
                    ],
                ),
            ):
                poll_until(lambda: _accepts(sim_port), 60, "the simulator listening")
                fcu = mavutil.mavlink_connection(
                    f"tcp:127.0.0.1:{sim_port}", source_system=250, source_component=190
                )
                try:
                    fcu.wait_heartbeat(timeout=30)
                    poll_until(
                        lambda: api.get(f"/api/v1/vehicles/{VEHICLE}").status_code == 200,
                        60,
                        f"{VEHICLE} connected to the hub",
                    )
                    yield CameraVehicle(api, hub_dir, photo_dir, proxy, fcu)
                finally:
                    fcu.close()
        finally:
            sim.terminate()
            sim.wait(10)


def _exif_position(path: Path) -> tuple[float, float, float]:
    with Image.open(path) as image:
        assert image.size == (320, 240)
        gps = image.getexif().get_ifd(ExifTags.IFD.GPSInfo)
    tags = ExifTags.GPS

    def degrees(key: int, ref: int) -> float:
        d, m, s = (float(v) for v in gps[key])
        return (d + m / 60 + s / 3600) * (-1 if gps[ref] in ("S", "W") else 1)

    return (
        degrees(tags.GPSLatitude, tags.GPSLatitudeRef),
        degrees(tags.GPSLongitude, tags.GPSLongitudeRef),
        float(gps[tags.GPSAltitude]),
    )


def test_photos_arrive_at_the_hub_geotagged_with_their_poses(vehicle: CameraVehicle) -> None:
    for _ in range(3):
        vehicle.fire()
    listed = poll_until(
        lambda: (p := vehicle.photos())["received"] >= 3 and p, 60, "3 photos stored at the hub"
    )
    assert listed["failed"] == 0
    for photo in listed["photos"]:
        pose = photo["pose"]
        # the vehicle stands at home: the pose is the autopilot's own at the shutter
        assert pose["lat"] == pytest.approx(DEFAULT_HOME.lat, abs=1e-5)
        assert pose["lon"] == pytest.approx(DEFAULT_HOME.lon, abs=1e-5)
        path = vehicle.hub_dir / "photos" / VEHICLE / f"{photo['photo_id']}.jpg"
        lat, lon, alt_msl = _exif_position(path)
        assert lat == pytest.approx(pose["lat"], abs=1e-7)
        assert lon == pytest.approx(pose["lon"], abs=1e-7)
        assert alt_msl == pytest.approx(pose["alt_msl"], abs=1e-3)
        with Image.open(path) as image:  # the ground's texture, not a blank frame
            low, high = image.convert("L").getextrema()
        assert high - low > 40


def test_photos_taken_while_the_hub_is_cut_off_arrive_after_it_returns(
    vehicle: CameraVehicle,
) -> None:
    before = vehicle.photos()["received"]
    vehicle.proxy.cut()
    try:
        for _ in range(3):
            vehicle.fire()
        poll_until(
            lambda: len(list(vehicle.photo_dir.glob("*.jpg"))) >= 3,
            60,
            "3 photos queued on the agent's disk",
        )
        assert vehicle.photos()["received"] == before  # none got through the cut
    finally:
        vehicle.proxy.start()
    poll_until(
        lambda: vehicle.photos()["received"] >= before + 3,
        90,
        "the queued photos stored at the hub after the link returned",
    )
    poll_until(
        lambda: not list(vehicle.photo_dir.glob("*.jpg")), 30, "the agent's photo queue emptied"
    )
