"""MosaicService on its own: bad photos are refused with their reasons and counted while
the mosaic goes on; coverage of the survey's area; tiles and progress outlive a restart;
the georeferencing agrees with morecantile's web-mercator."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import morecantile
import numpy as np
import pytest

from backend.imagery.mosaic.georef import TMS, to_mercator
from backend.imagery.mosaic.photo import StoredPhoto
from backend.imagery.mosaic.service import MosaicService
from protocol.photos import CameraIntrinsics
from simulator.world.ground import Ground
from tests.mosaic_photos import HOME, mosaic_of, survey_photos

CAMERA = CameraIntrinsics(
    sensor_width_mm=13.2,
    sensor_height_mm=8.8,
    image_width_px=320,
    image_height_px=240,
    focal_length_mm=8.8,
)
ALTITUDE_M = 20.0  # footprint 30 x 22.5 m


@pytest.fixture(scope="module")
def ground() -> Ground:
    return Ground(*HOME, seed=2)


def square_area(ground: Ground, half_m: float) -> dict[str, Any]:
    corners = [(-half_m, -half_m), (half_m, -half_m), (half_m, half_m), (-half_m, half_m)]
    ring = [ground.frame.to_geo(e, n)[::-1] for e, n in corners]
    return {"type": "Polygon", "coordinates": [[*ring, ring[0]]]}


def service_for(folder: Path, area: dict[str, Any] | None) -> MosaicService:
    async def area_of(_: str) -> dict[str, Any] | None:
        return area

    return MosaicService(folder, area_of)


def two_photos(tmp_path: Path, ground: Ground) -> list[StoredPhoto]:
    shots = [(0.0, -4.0, 0.0), (0.0, 4.0, 0.0)]
    return survey_photos(tmp_path / "photos", ground, CAMERA, shots, altitude_m=ALTITUDE_M)


def test_bad_photos_are_refused_with_their_reasons_and_the_mosaic_goes_on(
    tmp_path: Path, ground: Ground
) -> None:
    good, second = two_photos(tmp_path, ground)
    corrupt = tmp_path / "corrupt.jpg"
    corrupt.write_bytes(good.path.read_bytes()[:200])
    wrong_size = CAMERA.model_copy(update={"image_width_px": 640})
    far_lat, far_lon = ground.frame.to_geo(0.0, 5000.0)
    bad = [
        StoredPhoto("corrupt", "drone2", "s1", corrupt, good.pose, CAMERA),
        StoredPhoto("size", "drone2", "s1", good.path, good.pose, wrong_size),
        StoredPhoto(
            "tilted", "drone2", "s1", good.path, good.pose.model_copy(update={"roll": 45.0}), CAMERA
        ),
        StoredPhoto(
            "low", "drone2", "s1", good.path, good.pose.model_copy(update={"alt_rel": 0.2}), CAMERA
        ),
        StoredPhoto(
            "far",
            "drone2",
            "s1",
            good.path,
            good.pose.model_copy(update={"lat": far_lat, "lon": far_lon}),
            CAMERA,
        ),
        StoredPhoto("gone", "drone2", "s1", tmp_path / "missing.jpg", good.pose, CAMERA),
    ]
    service = service_for(tmp_path / "mosaics", square_area(ground, 20.0))
    asyncio.run(mosaic_of(service, [good, *bad, second]))
    progress = service.progress("s1")
    assert progress.processed == 2
    assert progress.failed == len(bad)
    assert progress.by_vehicle["drone1"].processed == 2
    assert progress.by_vehicle["drone2"].failed == len(bad)
    reasons = {failure.photo_id: failure.reason for failure in progress.failures}
    assert "not a readable JPEG" in reasons["corrupt"]
    assert "320 x 240 px but its camera model says 640 x 240" in reasons["size"]
    assert "tilted 45 degrees" in reasons["tilted"]
    assert "0.2 m above home" in reasons["low"]
    assert "from the survey's area" in reasons["far"]
    assert "missing.jpg" in reasons["gone"]
    assert progress.revision == 2


def test_coverage_of_the_area_and_its_outline(tmp_path: Path, ground: Ground) -> None:
    service = service_for(tmp_path / "mosaics", square_area(ground, 20.0))
    asyncio.run(mosaic_of(service, two_photos(tmp_path, ground)))
    progress = service.progress("s1")
    # Two 30 x 22.5 m footprints 8 m apart: 30 x 30.5 m, inside a 40 x 40 m area: 57%.
    assert progress.coverage_pct == pytest.approx(100 * 30 * 30.5 / 1600, abs=1.0)
    assert progress.outline is not None
    assert progress.outline["type"] == "Polygon"
    west, south, east, north = progress.bounds or (0, 0, 0, 0)
    assert west < HOME[1] < east
    assert south < HOME[0] < north


def test_tiles_progress_and_coverage_outlive_a_restart(tmp_path: Path, ground: Ground) -> None:
    folder = tmp_path / "mosaics"
    first = service_for(folder, None)
    asyncio.run(mosaic_of(first, two_photos(tmp_path, ground)))
    before = first.progress("s1")
    store = first.survey("s1").store
    zoom = store.max_zoom
    assert zoom is not None
    _, x, y = next(iter(store.keys(zoom)))
    tile = first.tile("s1", zoom, x, y)
    assert tile is not None

    again = service_for(folder, None)
    asyncio.run(again.load())
    assert again.surveys() == ["s1"]
    after = again.progress("s1")
    assert after.processed == before.processed
    assert after.revision == before.revision
    assert after.outline == before.outline
    reread = again.tile("s1", zoom, x, y)
    assert reread is not None
    assert (reread.data, reread.version) == (tile.data, tile.version)
    # Outside the mosaic: no tile, never an error.
    assert again.tile("s1", zoom, 0, 0) is None
    assert again.tile("s1", (again.survey("s1").store.min_zoom or 0) - 1, 0, 0) is None


def test_mercator_agrees_with_morecantile() -> None:
    lon = np.array([149.16523, -0.1276, 179.9])
    lat = np.array([-35.363261, 51.5072, 85.0])
    x, y = to_mercator(lon, lat)
    for i in range(3):
        expected = TMS.xy(lon[i], lat[i])
        assert x[i] == pytest.approx(expected.x, abs=1e-6)
        assert y[i] == pytest.approx(expected.y, abs=1e-6)
    assert isinstance(TMS, morecantile.TileMatrixSet)
