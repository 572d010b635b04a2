"""A mosaic out as files other tools open: a Cloud-Optimised GeoTIFF (GIS, OpenDroneMap's
output format), MBTiles and PMTiles (offline tile sets, which this hub's own base map
reads too: drop one in ``<data dir>/tiles``).

- COG: the native zoom's pixels in EPSG:3857 (the tiles' own grid, so nothing is
  resampled), RGBA, written tile by tile into a tiled GeoTIFF and then copied by GDAL's
  COG driver, which adds the overviews and orders the file for range reads.
- MBTiles 1.3: SQLite, the ``metadata`` table (name, format, bounds, center, zooms) and
  the ``tiles`` table in TMS row order (y from the south).
- PMTiles v3: the ``pmtiles`` package's writer, tiles in tile-id order.

Every zoom's tiles go in, as PNG (one format for the set; the live route's JPEG interiors
are for the wire). The caller holds the survey's lock, so no photo lands mid-export.
"""

from __future__ import annotations

import os
import sqlite3
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import rasterio
import rasterio.shutil
from pmtiles.tile import Compression, TileType, zxy_to_tileid
from pmtiles.writer import Writer
from rasterio import Affine
from rasterio.windows import Window

from backend.imagery.mosaic.georef import TILE_PX, WORLD_M
from backend.imagery.mosaic.store import TileKey, TileSpan, TileStore

FORMATS = {
    "tif": "image/tiff",
    "mbtiles": "application/vnd.sqlite3",
    "pmtiles": "application/vnd.pmtiles",
}
PMTilesWriter: Any = Writer  # the package has no type hints
MAX_COG_PX = 40_000  # a side; 1.6 gigapixels is beyond what a survey mosaic needs


class ExportError(ValueError):
    """A mosaic that cannot be exported (yet); the message says why."""


def _zooms(store: TileStore) -> tuple[int, int]:
    if store.max_zoom is None or store.min_zoom is None or not store.versions:
        raise ExportError("the mosaic has no tiles yet")
    return store.min_zoom, store.max_zoom


def _png(store: TileStore, key: TileKey) -> bytes:
    encoded = store.encode(key, always_png=True)
    if encoded is None:
        raise ExportError(f"tile {key} is missing")
    return encoded[0]


def _span(store: TileStore) -> tuple[TileSpan, list[TileKey]]:
    """The native zoom's tiles, and the block they cover."""
    _, zoom = _zooms(store)
    keys = list(store.keys(zoom))
    return TileSpan.of(zoom, keys), keys


def write_cog(store: TileStore, path: Path) -> Path:
    span, keys = _span(store)
    zoom, x0, y0 = span.zoom, span.x0, span.y0
    width, height = span.width_px, span.height_px
    if max(width, height) > MAX_COG_PX:
        raise ExportError(
            f"the mosaic is {width} x {height} px; a GeoTIFF export takes {MAX_COG_PX} a side"
        )
    res = WORLD_M / (TILE_PX * 2**zoom)
    profile: dict[str, Any] = {
        "driver": "GTiff",
        "width": width,
        "height": height,
        "count": 4,
        "dtype": "uint8",
        "crs": "EPSG:3857",
        # Built directly: rasterio's from_origin multiplies Affines with the `*` that
        # affine 3 deprecates.
        "transform": Affine(
            res, 0.0, x0 * TILE_PX * res - WORLD_M / 2, 0.0, -res, WORLD_M / 2 - y0 * TILE_PX * res
        ),
        "tiled": True,
        "blockxsize": TILE_PX,
        "blockysize": TILE_PX,
        "photometric": "RGB",
        "alpha": "YES",
    }
    with tempfile.TemporaryDirectory(dir=path.parent) as work:
        plain = Path(work) / "plain.tif"
        with rasterio.open(plain, "w", **profile) as raster:
            for key in keys:
                rgba = store.pixels(key)
                if rgba is None:
                    continue
                bands = np.transpose(rgba[:, :, [2, 1, 0, 3]], (2, 0, 1))  # BGRA -> RGBA
                window = Window(*span.offset_px(key), TILE_PX, TILE_PX)
                raster.write(bands, window=window)
        rasterio.shutil.copy(
            plain, path, driver="COG", compress="DEFLATE", overview_resampling="average"
        )
    return path


def write_mbtiles(store: TileStore, path: Path, name: str) -> Path:
    min_zoom, max_zoom = _zooms(store)
    west, south, east, north = _span(store)[0].bounds()
    metadata = {
        "name": name,
        "format": "png",
        "type": "overlay",
        "version": str(store.revision),
        "description": f"orthomosaic of survey {name}",
        "minzoom": str(min_zoom),
        "maxzoom": str(max_zoom),
        "bounds": f"{west},{south},{east},{north}",
        "center": f"{(west + east) / 2},{(south + north) / 2},{max_zoom}",
    }
    path.unlink(missing_ok=True)
    with sqlite3.connect(path) as db:
        db.execute("CREATE TABLE metadata (name TEXT, value TEXT)")
        db.execute(
            "CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER,"
            " tile_data BLOB)"
        )
        db.execute("CREATE UNIQUE INDEX tile_index ON tiles (zoom_level, tile_column, tile_row)")
        db.executemany("INSERT INTO metadata VALUES (?, ?)", metadata.items())
        for zoom in range(min_zoom, max_zoom + 1):
            db.executemany(
                "INSERT INTO tiles VALUES (?, ?, ?, ?)",
                ((z, x, (1 << z) - 1 - y, _png(store, (z, x, y))) for z, x, y in store.keys(zoom)),
            )
    db.close()
    return path


def write_pmtiles(store: TileStore, path: Path, name: str) -> Path:
    min_zoom, max_zoom = _zooms(store)
    west, south, east, north = _span(store)[0].bounds()
    keys = sorted(store.versions, key=lambda key: zxy_to_tileid(*key))
    with path.open("wb") as file:
        writer = PMTilesWriter(file)
        for key in keys:
            writer.write_tile(zxy_to_tileid(*key), _png(store, key))
        writer.finalize(
            {
                "tile_type": TileType.PNG,
                "tile_compression": Compression.NONE,
                "min_zoom": min_zoom,
                "max_zoom": max_zoom,
                "min_lon_e7": int(west * 1e7),
                "min_lat_e7": int(south * 1e7),
                "max_lon_e7": int(east * 1e7),
                "max_lat_e7": int(north * 1e7),
                "center_zoom": max_zoom,
                "center_lon_e7": int((west + east) / 2 * 1e7),
                "center_lat_e7": int((south + north) / 2 * 1e7),
            },
            {
                "name": name,
                "description": f"orthomosaic of survey {name}",
                "version": str(store.revision),
            },
        )
    return path


WRITERS: dict[str, Callable[[TileStore, Path, str], Path]] = {
    "tif": lambda store, path, _name: write_cog(store, path),
    "mbtiles": write_mbtiles,
    "pmtiles": write_pmtiles,
}


def export(store: TileStore, kind: str, folder: Path, name: str) -> Path:
    """The mosaic as a ``kind`` file (tif, mbtiles or pmtiles) in ``folder``, made once
    per revision of the mosaic: asked again before another photo lands, the same file.

    A file being served is never written over: each is built under a temporary name and
    renamed into place, and one of an older revision is only unlinked (a response still
    streaming it keeps reading it). Two viewers exporting at once each got a file the
    other was rewriting: 500s and cut-off files."""
    writer = WRITERS.get(kind)
    if writer is None:
        raise ExportError(f"no export as {kind!r}; one of {', '.join(FORMATS)}")
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}-r{store.revision}.{kind}"
    if path.exists():
        return path
    with tempfile.TemporaryDirectory(dir=folder) as work:
        made = writer(store, Path(work) / path.name, name)
        os.replace(made, path)
    for older in folder.glob(f"{name}-r*.{kind}"):
        if older != path:
            older.unlink(missing_ok=True)
    return path
