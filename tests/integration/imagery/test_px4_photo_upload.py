"""Photos from a simulated PX4 drone's camera to the hub, with real processes (the
simulator playing PX4, the agent, the hub): PX4 tells of each shutter with
CAMERA_IMAGE_CAPTURED and, where asked, CAMERA_TRIGGER; every shutter becomes one photo
at the hub and one camera event in the flight log (what a survey's progress counts),
a lane end's two shutters fired together included."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from pymavlink import mavutil

from simulator.config import DEFAULT_HOME
from tests.support.photos import camera_vehicle
from tests.support.waiting import poll_until

pytestmark = pytest.mark.integration

VEHICLE = "px4_cam_1"


@pytest.fixture(scope="module")
def px4_camera(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[httpx.Client, Any]]:
    with camera_vehicle(
        tmp_path_factory.mktemp("px4"),
        VEHICLE,
        ["--autopilot", "px4", "--camera", "tcp:127.0.0.1:{camera_port}"],
        "sim+http://127.0.0.1:{camera_port}",
        sim_camera_model=False,
    ) as (api, fcu, log):
        # The agent has asked for CAMERA_TRIGGER once its log says so.
        poll_until(
            lambda: "asked PX4 for CAMERA_TRIGGER" in log.read_text(errors="replace"),
            60,
            "the agent asking PX4 for CAMERA_TRIGGER",
        )
        yield api, fcu


def _fire(fcu: Any, shots: int) -> None:
    """DO_DIGICAM_CONTROL ``shots`` times in one write: the simulator fires them in one
    step, as a lane end's trigger-once and distance trigger fire together."""
    command = fcu.mav.command_long_encode(
        1, 1, mavutil.mavlink.MAV_CMD_DO_DIGICAM_CONTROL, 0, 0, 0, 0, 0, 1, 0, 0
    )
    fcu.write(b"".join(command.pack(fcu.mav) for _ in range(shots)))


def test_every_px4_shutter_is_one_photo_at_the_hub_and_one_camera_event(
    px4_camera: tuple[httpx.Client, Any],
) -> None:
    api, fcu = px4_camera
    _fire(fcu, 2)  # a lane end's pair
    _fire(fcu, 1)
    _fire(fcu, 2)

    def photos() -> dict[str, Any]:
        answer = api.get(f"/api/v1/vehicles/{VEHICLE}/photos", params={"limit": 1000})
        assert answer.status_code == 200, answer.text
        body: dict[str, Any] = answer.json()
        return body

    def camera_events() -> list[dict[str, Any]]:
        answer = api.get("/api/v1/events", params={"vehicle_id": VEHICLE, "kind": "camera"})
        assert answer.status_code == 200, answer.text
        events: list[dict[str, Any]] = answer.json()["events"]
        return events

    listed = poll_until(lambda: (p := photos())["received"] >= 5 and p, 60, "5 photos stored")
    poll_until(lambda: len(camera_events()) >= 5, 30, "5 camera events")
    # Nothing late doubles them: each shutter's second message was matched to its first.
    listed = photos()
    assert (listed["received"], listed["failed"]) == (5, 0)
    # <vehicle>-<exposure ms>-<PX4's shutter number>
    assert sorted(int(p["photo_id"].rsplit("-", 1)[1]) for p in listed["photos"]) == [0, 1, 2, 3, 4]
    for photo in listed["photos"]:
        assert photo["pose"]["lat"] == pytest.approx(DEFAULT_HOME.lat, abs=1e-5)
    # "photo <index> at <lat>, <lon>, <height> m above home"
    texts = [e["text"].split() for e in camera_events()]
    assert sorted(int(words[1]) for words in texts) == [0, 1, 2, 3, 4]
    assert all(
        float(words[3].rstrip(",")) == pytest.approx(DEFAULT_HOME.lat, abs=1e-5) for words in texts
    )
