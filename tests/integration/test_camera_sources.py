"""Photos from the two kinds of real camera beside the agent's own, with real processes:
the simulator as a MAVLink camera component (CAMERA_IMAGE_CAPTURED with its photo
server's address of each shot) and as a camera that writes its files into a folder, the
agent (``--camera mavlink``, ``--camera folder:DIR``) and the hub, whose photo store must
receive each shot's rendered photo, posed where the vehicle was.

The camera is fired by DO_DIGICAM_CONTROL, as a mission's camera command would; the
vehicle stays on the ground, over a ground laid 30 m below it.
"""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import httpx
import pytest
from PIL import Image
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.photos import parse_camera_model
from simulator import ListenAddress, SimulatorConfig
from simulator.config import DEFAULT_HOME
from tests.support.photos import CAMERA_MODEL, camera_vehicle
from tests.support.simulators import serving
from tests.support.waiting import poll_until, poll_until_async
from vehicle_agents.fcu.link import FcuLink

pytestmark = pytest.mark.integration


def _fire(fcu: Any, shots: int) -> None:
    for _ in range(shots):
        fcu.mav.command_long_send(
            1, 1, mavutil.mavlink.MAV_CMD_DO_DIGICAM_CONTROL, 0, 0, 0, 0, 0, 1, 0, 0
        )


def _stored(api: httpx.Client, vehicle: str, count: int) -> dict[str, Any]:
    def photos() -> dict[str, Any]:
        answer = api.get(f"/api/v1/vehicles/{vehicle}/photos", params={"limit": 1000})
        assert answer.status_code == 200, answer.text
        body: dict[str, Any] = answer.json()
        return body

    return poll_until(
        lambda: (p := photos())["received"] >= count and p, 90, f"{count} photos stored"
    )


def _assert_rendered_at_home(hub_dir: Path, vehicle: str, listed: dict[str, Any]) -> None:
    for photo in listed["photos"]:
        assert photo["pose"]["lat"] == pytest.approx(DEFAULT_HOME.lat, abs=1e-5)
        assert photo["pose"]["lon"] == pytest.approx(DEFAULT_HOME.lon, abs=1e-5)
        with Image.open(hub_dir / "photos" / vehicle / f"{photo['photo_id']}.jpg") as image:
            assert image.size == (320, 240)
            low, high = image.convert("L").getextrema()
        assert high - low > 40  # the ground's texture, not a blank frame


def test_a_mavlink_cameras_photos_reach_the_hub(tmp_path: Path) -> None:
    vehicle = "mavcam_1"
    with camera_vehicle(
        tmp_path,
        vehicle,
        ["--camera", "tcp:127.0.0.1:{camera_port}", "--camera-component"],
        "mavlink",
    ) as (api, fcu, _log):
        _fire(fcu, 3)
        listed = _stored(api, vehicle, 3)
        assert (listed["received"], listed["failed"]) == (3, 0)
        # <vehicle>-<exposure ms>-<the camera's own image number, from 0>
        assert sorted(int(p["photo_id"].rsplit("-", 1)[1]) for p in listed["photos"]) == [0, 1, 2]
        _assert_rendered_at_home(tmp_path / "hub", vehicle, listed)
        # The autopilot's CAMERA_FEEDBACK of the same shutters made no photos of their own.
        assert _stored(api, vehicle, 3)["received"] == 3


def test_a_folder_cameras_files_reach_the_hub_paired_with_the_triggers(tmp_path: Path) -> None:
    vehicle = "foldercam_1"
    card = tmp_path / "card" / "DCIM"
    card.mkdir(parents=True)
    (card / "DSC09999.JPG").write_bytes(b"an earlier flight's photo")  # never uploaded
    with camera_vehicle(tmp_path, vehicle, ["--camera-folder", str(card)], f"folder:{card}") as (
        api,
        fcu,
        log,
    ):
        poll_until(
            lambda: "files there before the start" in log.read_text(errors="replace"),
            30,
            "the agent watching the folder",
        )
        _fire(fcu, 3)
        listed = _stored(api, vehicle, 3)
        assert (listed["received"], listed["failed"]) == (3, 0)
        # ArduPilot's shot counter, from 1: each file went with its own trigger, in order
        photos = sorted(listed["photos"], key=lambda p: int(p["photo_id"].rsplit("-", 1)[1]))
        assert [int(p["photo_id"].rsplit("-", 1)[1]) for p in photos] == [1, 2, 3]
        _assert_rendered_at_home(tmp_path / "hub", vehicle, listed)
        text = log.read_text(errors="replace")
        for index, name in ((1, "DSC00001.JPG"), (2, "DSC00002.JPG"), (3, "DSC00003.JPG")):
            assert f"photo {index} is {card / name}" in text
        assert "not uploaded" not in text
    assert (card / "DSC09999.JPG").exists()  # the card is the camera's: nothing deleted


def test_a_cameras_heartbeat_is_not_taken_for_the_autopilots() -> None:
    """A MAVLink camera's heartbeats (MAV_TYPE_CAMERA, base mode 0) beside an armed
    autopilot's: the agent's link keeps the autopilot's."""
    config = SimulatorConfig(
        listen=ListenAddress("tcp", "127.0.0.1", 0),
        camera=ListenAddress("tcp", "127.0.0.1", 0),
        camera_component=True,
        camera_model=parse_camera_model(CAMERA_MODEL),
    )

    async def heartbeats(port: int) -> tuple[set[int], int]:
        """The components whose heartbeat the link held as the autopilot's, at every
        message it delivered while three of the camera's came in."""
        link = FcuLink(f"tcp:127.0.0.1:{port}")
        cameras: list[Any] = []
        link.taps.append(  # on the reader thread, before the message reaches the loop
            lambda m: (
                cameras.append(m)
                if m.get_type() == "HEARTBEAT"
                and m.get_srcComponent() == mavlink2.MAV_COMP_ID_CAMERA
                else None
            )
        )
        held: set[int] = set()
        link.listeners.append(
            lambda m: (
                held.add(link.latest["HEARTBEAT"].get_srcComponent())
                if "HEARTBEAT" in link.latest
                else None
            )
        )
        async with asyncio.TaskGroup() as tasks:
            running = tasks.create_task(link.run())
            await asyncio.wait_for(link.wait_identified(), 10)
            await poll_until_async(lambda: len(cameras) >= 3, 20, "three camera heartbeats")
            # a message after the last of them: it has been through the loop's delivery
            assert await link.wait_for(lambda m: True, 5) is not None
            running.cancel()
        return held, len(cameras)

    with serving(config) as (_server, address):
        held, cameras = asyncio.run(heartbeats(address.port))
    assert cameras >= 3
    assert held == {1}
