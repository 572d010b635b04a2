"""The live orthomosaic with 12 MP photos: photos per second into tiles, and the delay from
a stored photo to its tiles being servable.

    .venv/bin/python bench/bench_mosaic.py              # a minute or two on 2 cores
    options: --photos 24 --unique 4 --rate 1.0 --altitude 60

Figures and their bars (issue 21):
- photos per second into tiles, 12 MP (4000 x 3000) photos queued all at once, every zoom
  from the native one (about 2 cm pixels) down to the overviews: >= 2 photos/s;
- the delay from ``MosaicService.add_photo`` (the ingest route's hand-over, once the upload
  is stored) to the photo's tiles written and one of them encoded as the route serves it,
  with photos arriving at ``--rate`` per second (a fleet's camera triggers): p50 and p99.

The photos are the simulated camera's nadir views of the synthetic ground (rendering one
takes seconds, so ``--unique`` are rendered and reused along the lanes with their own
poses: the mosaic's work does not depend on what the pixels show). Prints a table;
asserts nothing.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
import tempfile
import time
from pathlib import Path

from backend.imagery.mosaic.engine import Applied
from backend.imagery.mosaic.photo import StoredPhoto
from backend.imagery.mosaic.service import MosaicService
from protocol.photos import CameraIntrinsics
from simulator.world.ground import Ground
from tests.mosaic_photos import HOME, lane_poses, survey_photos

# A 1/2.3" 12 MP drone camera (DJI Mavic 2 Zoom / Mini class): 6.3 x 4.7 mm, 4000 x 3000 px.
CAMERA = CameraIntrinsics(
    sensor_width_mm=6.3,
    sensor_height_mm=4.7,
    image_width_px=4000,
    image_height_px=3000,
    focal_length_mm=4.5,
)


def photos_for(folder: Path, count: int, unique: int, altitude_m: float) -> list[StoredPhoto]:
    ground = Ground.around(*HOME, extent_m=90.0, spacing_m=30.0)
    # 70 % side and 80 % front overlap of an 84 x 63 m footprint.
    shots = list(
        lane_poses(
            ground.frame,
            altitude_m=altitude_m,
            lanes_east_m=[-50.0 + 25.0 * i for i in range(5)],
            north_from_m=-60.0,
            north_to_m=60.0,
            step_m=12.5,
        )
    )[:count]
    started = time.perf_counter()
    rendered = survey_photos(folder, ground, CAMERA, shots[:unique], altitude_m=altitude_m)
    print(f"rendered {unique} 12 MP photos in {time.perf_counter() - started:.1f} s")
    photos = []
    for index, (east, north, yaw) in enumerate(shots):
        source = rendered[index % unique]
        lat, lon = ground.frame.to_geo(east, north)
        pose = source.pose.model_copy(update={"lat": lat, "lon": lon, "yaw": yaw})
        photos.append(StoredPhoto(f"p{index}", "drone1", "bench", source.path, pose, CAMERA))
    return photos


async def burst(folder: Path, photos: list[StoredPhoto]) -> tuple[float, float, list[float]]:
    async def no_area(_: str) -> None:
        return None

    service = MosaicService(folder, no_area)
    each: list[float] = []
    last = [time.perf_counter()]

    def done(photo: StoredPhoto, applied: Applied | None) -> None:
        now = time.perf_counter()
        each.append(now - last[0])
        last[0] = now

    service.listeners.append(done)
    worker = asyncio.create_task(service.run())
    started = time.perf_counter()
    cpu = time.process_time()
    last[0] = started
    for photo in photos:
        await service.add_photo(photo)
    await service.idle()
    elapsed = time.perf_counter() - started
    cpu_per_photo = (time.process_time() - cpu) / len(photos)
    worker.cancel()
    await asyncio.gather(worker, return_exceptions=True)
    progress = service.progress("bench")
    assert progress.failed == 0, progress.failures
    tiles = len(service.survey("bench").store.versions)
    print(
        f"burst: {len(photos)} photos, {tiles} tiles, zooms {progress.min_zoom}-{progress.max_zoom}"
    )
    return len(photos) / elapsed, cpu_per_photo, each


async def paced(folder: Path, photos: list[StoredPhoto], rate: float) -> list[float]:
    async def no_area(_: str) -> None:
        return None

    service = MosaicService(folder, no_area)
    added: dict[str, float] = {}
    delays: list[float] = []
    loop = asyncio.get_running_loop()

    def done(photo: StoredPhoto, applied: Applied | None) -> None:
        # In the worker thread, as the route would: the first tile written, encoded.
        if applied and applied.tiles:
            service.tile("bench", *applied.tiles[0])
        delays.append(time.perf_counter() - added[photo.photo_id])

    service.listeners.append(done)
    worker = asyncio.create_task(service.run())
    for photo in photos:
        added[photo.photo_id] = time.perf_counter()
        await service.add_photo(photo)
        await asyncio.sleep(1.0 / rate)
    await service.idle()
    worker.cancel()
    await asyncio.gather(worker, return_exceptions=True)
    del loop
    return delays


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--photos", type=int, default=24)
    parser.add_argument("--unique", type=int, default=4)
    parser.add_argument("--rate", type=float, default=1.0, help="photos per second, paced run")
    parser.add_argument("--altitude", type=float, default=60.0)
    args = parser.parse_args()
    # On a shared machine the wall-clock rate is partly the machine's: the load average
    # and the CPU time per photo say how much.
    print(f"{os.cpu_count()} cores; load average {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as work:
        root = Path(work)
        photos = photos_for(root / "photos", args.photos, args.unique, args.altitude)
        rate, cpu, each = asyncio.run(burst(root / "burst", photos))
        delays = asyncio.run(paced(root / "paced", photos, args.rate))
    print()
    print(f"{'figure':58} {'value':>12}  bar")
    print(f"{'photos per second into tiles (12 MP, all zooms)':58} {rate:12.2f}  >= 2")
    print(
        f"{'  per photo, median / worst (s)':58} {statistics.median(each):5.2f} / {max(each):4.2f}"
    )
    print(f"{'  CPU per photo, all threads (s)':58} {cpu:12.2f}")
    label = f"add_photo -> tile servable, at {args.rate:g} photo/s: p50 (s)"
    print(f"{label:58} {percentile(delays, 0.5):12.2f}")
    print(f"{'  p99 (s)':58} {percentile(delays, 0.99):12.2f}")


if __name__ == "__main__":
    main()
