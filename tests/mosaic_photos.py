"""Survey photos without a flight: the simulated camera's nadir views along lanes over the
synthetic ground, written as JPEGs, with their exact (or noisy) poses; and reading a
mosaic's tiles back to find the ground targets in them. Shared by the mosaic's tests and
bench/bench_mosaic.py."""

from __future__ import annotations

import asyncio
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

from backend.imagery.mosaic.georef import TILE_PX, pixel_to_lonlat
from backend.imagery.mosaic.photo import StoredPhoto
from backend.imagery.mosaic.service import MosaicService
from common.camera_geometry import gsd_m
from common.geodesy import LocalFrame
from protocol.photos import CameraIntrinsics, PhotoPose
from simulator.sensors.camera import render_nadir
from simulator.world.ground import ARUCO_DICTIONARY, Ground

HOME = (-35.363261, 149.165230, 584.0)  # ArduPilot's SITL home, as the simulator's


@dataclass(frozen=True)
class Noise:
    """Pose errors of a drone without RTK: GNSS horizontal and vertical (1 sigma, metres)
    and attitude (1 sigma, degrees)."""

    horizontal_m: float = 0.0
    vertical_m: float = 0.0
    attitude_deg: float = 0.0


EXACT = Noise()
NO_RTK = Noise(horizontal_m=1.0, vertical_m=1.5, attitude_deg=1.5)


def lane_poses(
    frame: LocalFrame,
    *,
    altitude_m: float,
    lanes_east_m: list[float],
    north_from_m: float,
    north_to_m: float,
    step_m: float,
) -> Iterator[tuple[float, float, float]]:
    """(east, north, yaw) of each shot, lawnmower fashion: up the first lane, down the next."""
    norths = list(np.arange(north_from_m, north_to_m + 1e-9, step_m))
    for lane, east in enumerate(lanes_east_m):
        going_north = lane % 2 == 0
        for north in norths if going_north else norths[::-1]:
            yield east, float(north), 0.0 if going_north else 180.0


def survey_photos(
    folder: Path,
    ground: Ground,
    camera: CameraIntrinsics,
    shots: list[tuple[float, float, float]],
    *,
    altitude_m: float,
    survey_id: str = "s1",
    vehicle_id: str = "drone1",
    noise: Noise = EXACT,
    seed: int = 3,
) -> list[StoredPhoto]:
    """Render each shot with its true pose; the StoredPhoto carries the pose the drone
    would have reported (the truth plus ``noise``)."""
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    frame = ground.frame
    photos = []
    for index, (east, north, yaw) in enumerate(shots):
        lat, lon = frame.to_geo(east, north)
        truth = PhotoPose(
            lat=lat,
            lon=lon,
            alt_msl=ground.elevation_msl + altitude_m,
            alt_rel=altitude_m,
            roll=0.0,
            pitch=0.0,
            yaw=yaw,
            time=1_700_000_000.0 + index,
        )
        path = folder / f"{vehicle_id}-{index:04d}.jpg"
        image = render_nadir(truth, camera, ground)
        cv2.imwrite(str(path), image[:, :, ::-1], [cv2.IMWRITE_JPEG_QUALITY, 92])
        de, dn = rng.normal(0.0, noise.horizontal_m, 2)
        reported_lat, reported_lon = frame.to_geo(east + de, north + dn)
        droll, dpitch, dyaw = rng.normal(0.0, noise.attitude_deg, 3)
        reported = truth.model_copy(
            update={
                "lat": reported_lat,
                "lon": reported_lon,
                "alt_rel": altitude_m + float(rng.normal(0.0, noise.vertical_m)),
                "roll": float(droll),
                "pitch": float(dpitch),
                "yaw": yaw + float(dyaw),
            }
        )
        photos.append(
            StoredPhoto(f"{vehicle_id}-{index}", vehicle_id, survey_id, path, reported, camera)
        )
    return photos


async def mosaic_of(service: MosaicService, photos: list[StoredPhoto]) -> None:
    """Feed the photos to the service's worker and wait until they are all done."""
    worker = asyncio.create_task(service.run())
    try:
        for photo in photos:
            await service.add_photo(photo)
        await service.idle()
    finally:
        worker.cancel()
        await asyncio.gather(worker, return_exceptions=True)


def stitched(
    service: MosaicService, survey_id: str, zoom: int
) -> tuple[npt.NDArray[np.uint8], int, int]:
    """The zoom's tiles, as served (decoded), laid side by side: the image, and the global
    pixel column and row of its top-left corner."""
    store = service.survey(survey_id).store
    keys = list(store.keys(zoom))
    x0, y0 = min(k[1] for k in keys), min(k[2] for k in keys)
    width = (max(k[1] for k in keys) - x0 + 1) * TILE_PX
    height = (max(k[2] for k in keys) - y0 + 1) * TILE_PX
    image = np.zeros((height, width, 3), np.uint8)
    for _, x, y in keys:
        served = service.tile(survey_id, zoom, x, y)
        assert served is not None
        tile = cv2.imdecode(np.frombuffer(served.data, np.uint8), cv2.IMREAD_COLOR)
        top, left = (y - y0) * TILE_PX, (x - x0) * TILE_PX
        image[top : top + TILE_PX, left : left + TILE_PX] = tile
    return image, x0 * TILE_PX, y0 * TILE_PX


def target_errors_m(service: MosaicService, survey_id: str, ground: Ground) -> dict[int, float]:
    """Each ground target found in the native-zoom tiles: how far (metres) the position the
    mosaic gives it lies from where it is."""
    zoom = service.survey(survey_id).store.max_zoom
    assert zoom is not None
    image, left, top = stitched(service, survey_id, zoom)
    return marker_errors_m(image, left, top, zoom, ground)


def marker_errors_m(
    image: npt.NDArray[np.uint8], left: int, top: int, zoom: int, ground: Ground
) -> dict[int, float]:
    """The ground targets found in ``image`` (tiles of ``zoom`` laid side by side, its
    top-left corner at global pixel ``left``, ``top``): each one's distance in metres from
    where it truly lies."""
    detector = cv2.aruco.ArucoDetector(
        cv2.aruco.getPredefinedDictionary(ARUCO_DICTIONARY), cv2.aruco.DetectorParameters()
    )
    corners, ids, _ = detector.detectMarkers(image)
    truth = {target.marker_id: target for target in ground.targets}
    frame = ground.frame
    errors: dict[int, float] = {}
    for found, marker_id in zip(corners, [] if ids is None else ids.ravel(), strict=True):
        u, v = (float(c) for c in found.reshape(4, 2).mean(axis=0))
        # Tile pixel (i, j) covers [i, i + 1) of the global grid: its centre is i + 0.5.
        lon, lat = pixel_to_lonlat(zoom, left + u + 0.5, top + v + 0.5)
        target = truth.get(int(marker_id))
        if target is None:  # a false detection in the texture: no such target
            continue
        errors[int(marker_id)] = math.dist(
            frame.to_local(lat, lon), frame.to_local(target.lat, target.lon)
        )
    return errors


def photo_gsd_m(camera: CameraIntrinsics, altitude_m: float) -> float:
    return gsd_m(camera, altitude_m)
