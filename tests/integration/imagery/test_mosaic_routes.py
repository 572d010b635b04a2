"""The hub serves each survey's live mosaic: progress, tiles with versions, and the
exports (COG, MBTiles, PMTiles) read back with rasterio, SQLite and the pmtiles reader.
The mosaic is built beforehand by MosaicService in the hub's data folder, and the hub
finds it at start-up as it would after a restart."""

from __future__ import annotations

import asyncio
import mmap
import sqlite3
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import httpx
import pytest
import rasterio
from pmtiles.reader import Reader

from backend.imagery.mosaic.georef import TMS
from backend.imagery.mosaic.service import MosaicService
from protocol.photos import CameraIntrinsics
from simulator.world.ground import Ground
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.mosaic_photos import HOME, mosaic_of, survey_photos
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub

SURVEY = "5e1f0a9b2c3d"
CAMERA = CameraIntrinsics(
    sensor_width_mm=13.2,
    sensor_height_mm=8.8,
    image_width_px=640,
    image_height_px=480,
    focal_length_mm=8.8,
)
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@dataclass
class Built:
    api: httpx.Client
    zoom: tuple[int, int]
    inner: tuple[int, int, int]  # a tile inside the mosaic


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Built]:
    """One hub for the module: the tests read, and the last adds a base map."""
    tmp_path = tmp_path_factory.mktemp("mosaic_hub")
    ground = Ground(*HOME, seed=4)
    shots = [(-6.0, -6.0, 0.0), (-6.0, 6.0, 0.0), (6.0, 6.0, 180.0), (6.0, -6.0, 180.0)]
    photos = survey_photos(
        tmp_path / "photos", ground, CAMERA, shots, altitude_m=20.0, survey_id=SURVEY
    )

    async def no_area(_: str) -> None:
        return None

    service = MosaicService(tmp_path / "mosaics", no_area)
    asyncio.run(mosaic_of(service, photos))
    service.close()
    store = service.survey(SURVEY).store
    assert store.min_zoom is not None
    assert store.max_zoom is not None
    opaque = [key for key in store.keys(store.max_zoom) if store.pixels(key)[:, :, 3].min() == 255]  # type: ignore[index]
    with running_hub(hub_settings(tmp_path)) as base_url:
        token = access_token(base_url, "admin", ADMIN_PASSWORD)
        with api_client(base_url, token) as api:
            yield Built(api, (store.min_zoom, store.max_zoom), opaque[0])


def test_progress_and_a_versioned_tile(built: Built) -> None:
    api = built.api
    listed = api.get("/api/v1/mosaics")
    assert listed.status_code == 200, listed.text
    assert [m["survey_id"] for m in listed.json()] == [SURVEY]
    detail = api.get(f"/api/v1/mosaics/{SURVEY}").json()
    assert (detail["processed"], detail["failed"], detail["revision"]) == (4, 0, 4)
    assert (detail["min_zoom"], detail["max_zoom"]) == built.zoom
    assert detail["coverage_pct"] is None  # no survey of that id: no area to cover
    assert detail["outline"]["type"] == "Polygon"
    z, x, y = built.inner
    tile = api.get(detail["tile_url"].format(z=z, x=x, y=y))
    assert tile.status_code == 200
    assert tile.headers["content-type"] == "image/jpeg"
    assert tile.headers["cache-control"] == "private, no-cache"
    assert int(tile.headers["x-tile-version"]) >= 1
    again = api.get(tile.url, headers={"If-None-Match": tile.headers["etag"]})
    assert again.status_code == 304


def test_outside_the_mosaic_is_a_404_and_bad_paths_a_422(built: Built) -> None:
    api = built.api
    z, x, y = built.inner
    outside = api.get(f"/api/v1/mosaics/{SURVEY}/tiles/{z}/{x + 50}/{y}")
    assert outside.status_code == 404
    assert "no tile" in outside.json()["detail"]
    assert outside.headers["cache-control"] == "private, max-age=5"
    assert api.get(f"/api/v1/mosaics/{SURVEY}/tiles/3/1/1").status_code == 404
    unknown = api.get(f"/api/v1/mosaics/abc123/tiles/{z}/{x}/{y}")
    assert unknown.status_code == 404
    assert "abc123" in unknown.json()["detail"]
    assert api.get("/api/v1/mosaics/abc123").status_code == 404
    assert api.get(f"/api/v1/mosaics/{SURVEY}/tiles/2/4/0").status_code == 422
    assert api.get(f"/api/v1/mosaics/..%2Fx/tiles/{z}/{x}/{y}").status_code in (404, 422)
    assert api.get(f"/api/v1/mosaics/{SURVEY}/export.zip").status_code == 422


def test_the_exports_open_with_rasterio_sqlite_and_pmtiles(built: Built, tmp_path: Path) -> None:
    api = built.api
    min_zoom, max_zoom = built.zoom
    home_x, home_y = TMS.xy(HOME[1], HOME[0])

    cog = tmp_path / "mosaic.tif"
    cog.write_bytes(api.get(f"/api/v1/mosaics/{SURVEY}/export.tif").raise_for_status().content)
    with rasterio.open(cog) as raster:
        assert raster.crs.to_epsg() == 3857
        assert raster.count == 4
        left, bottom, right, top = raster.bounds
        assert left < home_x < right
        assert bottom < home_y < top
        assert raster.overviews(1)  # cloud-optimised: the overviews are in the file
        assert raster.read(4).max() == 255  # the photos' pixels are opaque

    mbtiles = tmp_path / "mosaic.mbtiles"
    got = api.get(f"/api/v1/mosaics/{SURVEY}/export.mbtiles").raise_for_status()
    mbtiles.write_bytes(got.content)
    with sqlite3.connect(mbtiles) as db:
        metadata = dict(db.execute("SELECT name, value FROM metadata").fetchall())
        zooms = db.execute("SELECT MIN(zoom_level), MAX(zoom_level) FROM tiles").fetchone()
        z, x, y = built.inner
        row = db.execute(
            "SELECT tile_data FROM tiles WHERE zoom_level=? AND tile_column=? AND tile_row=?",
            (z, x, (1 << z) - 1 - y),
        ).fetchone()
    db.close()
    assert metadata["format"] == "png"
    assert (int(metadata["minzoom"]), int(metadata["maxzoom"])) == (min_zoom, max_zoom)
    west, south, east, north = (float(v) for v in metadata["bounds"].split(","))
    assert west < HOME[1] < east
    assert south < HOME[0] < north
    assert tuple(zooms) == (min_zoom, max_zoom)
    assert bytes(row[0]).startswith(PNG_SIGNATURE)

    pmtiles = tmp_path / "mosaic.pmtiles"
    pmtiles.write_bytes(
        api.get(f"/api/v1/mosaics/{SURVEY}/export.pmtiles").raise_for_status().content
    )
    with pmtiles.open("rb") as file, mmap.mmap(file.fileno(), 0, access=mmap.ACCESS_READ) as data:
        reader = Reader(lambda offset, length: data[offset : offset + length])
        header = reader.header()
        assert (header["min_zoom"], header["max_zoom"]) == (min_zoom, max_zoom)
        assert reader.get(*built.inner).startswith(PNG_SIGNATURE)
        assert reader.get(*built.inner) == bytes(row[0])


def test_the_mosaic_becomes_an_offline_base_map(built: Built) -> None:
    api = built.api
    installed = api.post(f"/api/v1/mosaics/{SURVEY}/basemap")
    assert installed.status_code == 200, installed.text
    tile_set = installed.json()
    assert tile_set["name"] == f"mosaic-{SURVEY}"
    assert (tile_set["kind"], tile_set["media_type"]) == ("pmtiles", "image/png")
    assert tile_set["max_zoom"] == built.zoom[1]
    listed = {s["name"]: s for s in api.get("/api/v1/tiles").json()}
    assert f"mosaic-{SURVEY}" in listed
    z, x, y = built.inner
    tile = api.get(tile_set["url"].format(z=z, x=x, y=y))
    assert tile.status_code == 200
    assert tile.content.startswith(PNG_SIGNATURE)
    assert api.post("/api/v1/mosaics/abc123/basemap").status_code == 404


def test_exports_asked_at_once_are_one_whole_file_for_everyone(built: Built) -> None:
    """Six viewers asking for the same export at once each get the whole file, the same
    one: it is built once, under a temporary name renamed into place (each rewrote the
    file the others were reading: 500s and cut-off files)."""
    base_url = str(built.api.base_url)
    headers = dict(built.api.headers)

    def fetch(kind: str) -> tuple[int, bytes]:
        with httpx.Client(base_url=base_url, headers=headers, timeout=60) as client:
            got = client.get(f"/api/v1/mosaics/{SURVEY}/export.{kind}")
            return got.status_code, got.content

    for kind in ("pmtiles", "mbtiles", "tif"):
        with ThreadPoolExecutor(6) as pool:
            answers = list(pool.map(fetch, [kind] * 6))
        assert [status for status, _ in answers] == [200] * 6, kind
        assert len({content for _, content in answers}) == 1, f"{kind}: different files"
