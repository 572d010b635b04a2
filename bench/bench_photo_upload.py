"""Photos from the agent to the hub, 12 MP: the agent's geotagging, the hub's check of a
whole JPEG, and the upload's throughput through a real hub, paced and unpaced.

    .venv/bin/python bench/bench_photo_upload.py          # about a minute on 2 cores
    options: --photos 6 --paced 3

- geotag: EXIF and XMP inserted into a 12 MP JPEG (piexif, no re-encode), per photo;
- check: the hub's truncation/corruption check (a decode at 1/8 scale), per photo;
- upload: the agent's PhotoUploader (256 KiB chunks, one photo at a time) to an in-process
  hub on loopback: MB/s and photos/s with no pacing, then the rate it keeps with the
  default 2 MiB/s pacing (what leaves a narrow link room for telemetry).

The photo is the simulated camera's nadir view of the synthetic ground. Prints figures;
asserts nothing.
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import tempfile
import time
from pathlib import Path

from backend.imagery.photos.checks import check_image
from common.geodesy import GeoPoint
from protocol.photos import CameraIntrinsics, PhotoMeta, PhotoPose
from simulator.outputs.photos import nadir_renderer
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.integration.test_hub_bad_input import scripted_agent
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub
from tests.support.waiting import poll_until_async
from vehicle_agents.camera.geotag import geotag
from vehicle_agents.camera.queue import MIB, PhotoQueue
from vehicle_agents.camera.upload import PhotoUploader

CAMERA = CameraIntrinsics(
    sensor_width_mm=6.3,
    sensor_height_mm=4.7,
    image_width_px=4000,
    image_height_px=3000,
    focal_length_mm=4.5,
)
HOME = GeoPoint(-35.363262, 149.165237, 584.0)
VEHICLE = "bench_1"


def pose(index: int) -> PhotoPose:
    return PhotoPose(
        lat=HOME.lat + index * 1e-5,
        lon=HOME.lon,
        alt_msl=HOME.alt + 60,
        alt_rel=60,
        roll=0,
        pitch=0,
        yaw=0,
        time=1.7e9 + index,
    )


def timed(function: object, repeats: int) -> float:
    """The median seconds of ``repeats`` calls of a no-argument callable."""
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()  # type: ignore[operator]
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def upload(hub: str, token: str, folder: Path, jpeg: bytes, count: int, rate: float) -> float:
    """Seconds to upload ``count`` photos at ``rate`` bytes/s."""
    queue = PhotoQueue(folder, budget_bytes=count * len(jpeg) * 2)
    for index in range(count):
        tagged = geotag(jpeg, pose(index), CAMERA, model="bench")
        meta = PhotoMeta(
            photo_id=f"{folder.name}-{index}",
            index=index,
            size_bytes=len(tagged),
            pose=pose(index),
            camera=CAMERA,
        )
        queue.put(meta, tagged)
    uploader = PhotoUploader(queue, hub, VEHICLE, token, rate_bytes_per_s=rate)

    async def run() -> float:
        started = time.perf_counter()
        task = asyncio.create_task(uploader.run())
        await poll_until_async(lambda: not len(queue), 600, "the queue sent", every_s=0.01)
        elapsed = time.perf_counter() - started
        task.cancel()
        return elapsed

    elapsed = asyncio.run(run())
    assert uploader.stats.uploaded == count, uploader.stats
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photos", type=int, default=6, help="photos sent unpaced")
    parser.add_argument("--paced", type=int, default=3, help="photos sent at 2 MiB/s")
    args = parser.parse_args()

    started = time.perf_counter()
    jpeg = nadir_renderer(HOME)(pose(0), CAMERA)
    rendered_s = time.perf_counter() - started
    print(f"12 MP photo: {len(jpeg) / MIB:.2f} MiB (rendered in {rendered_s:.1f} s)")
    tag_s = timed(lambda: geotag(jpeg, pose(0), CAMERA, model="b"), 20)
    print(f"geotag (EXIF + XMP, no re-encode): {tag_s * 1e3:.2f} ms per photo")
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        path = folder / "photo.jpg"
        path.write_bytes(jpeg)
        check_s = timed(lambda: check_image(path, CAMERA), 5)
        print(f"hub check (whole JPEG, 1/8-scale decode): {check_s * 1e3:.0f} ms per photo")
        settings = hub_settings(folder / "hub", max_photo_bytes_per_vehicle=10 * 1024**3)
        with running_hub(settings) as hub:
            with api_client(hub, access_token(hub, "admin", ADMIN_PASSWORD)) as api:
                token = api.post(f"/api/v1/vehicles/{VEHICLE}/agent-tokens").json()["token"]
            with scripted_agent(hub, VEHICLE, token):
                pass
            size = len(geotag(jpeg, pose(0), CAMERA, model="bench"))
            elapsed = upload(hub, token, folder / "fast", jpeg, args.photos, 1e12)
            rate = args.photos * size / MIB / elapsed
            print(
                f"upload, unpaced, {args.photos} photos: {rate:.1f} MiB/s, "
                f"{args.photos / elapsed:.2f} photos/s"
            )
            elapsed = upload(hub, token, folder / "paced", jpeg, args.paced, 2 * MIB)
            print(
                f"upload, paced at 2 MiB/s, {args.paced} photos: "
                f"{args.paced * size / MIB / elapsed:.2f} MiB/s"
            )


if __name__ == "__main__":
    main()
