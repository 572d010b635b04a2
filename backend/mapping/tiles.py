"""Offline tile sets: ``.mbtiles`` and ``.pmtiles`` files in one folder, read by name.

Pure domain with file I/O only: no HTTP here (``backend/api/tiles.py`` serves them). A
set's name is its file name without the suffix; a file that is added, replaced or removed
is noticed at the next listing or tile read (its size and modification time are checked),
so dropping a file in the folder is enough, with no restart.

MBTiles is SQLite with rows in TMS order (y counted from the south), so a request's XYZ
``y`` is flipped, against the height of web Mercator's tile matrix at its zoom (the
MBTiles 1.3 specification). PMTiles is read with the ``pmtiles`` package, already in XYZ
order. The grid is morecantile's WebMercatorQuad, as the mosaic's
(backend/imagery/mosaic/georef.py).
"""

from __future__ import annotations

import gzip
import hashlib
import logging
import mmap
import re
import sqlite3
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import morecantile
import pyproj
from pmtiles.reader import Reader
from pmtiles.tile import Compression, TileType

log = logging.getLogger(__name__)

PMTilesReader: Any = Reader  # the package has no type hints

SUFFIXES = (".mbtiles", ".pmtiles")
# What a set may be called: its file name without the suffix, safe in a URL and a path.
NAME_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
MAX_ZOOM = 30
# morecantile's WebMercatorQuad stops at zoom 24 and makes each deeper matrix again, with a
# warning, at every call: the same grid, down to the deepest zoom the routes accept.
WEB_MERCATOR = morecantile.TileMatrixSet.custom(
    list(morecantile.tms.get("WebMercatorQuad").xy_bbox),
    pyproj.CRS.from_epsg(3857),
    maxzoom=MAX_ZOOM,
    id="WebMercatorQuad",
)
RESCAN_S = 1.0
# Raster formats a browser draws as an <img>; vector tiles (pbf/MVT) need a renderer the
# dashboard does not have, so such a set is refused with that reason.
MEDIA_TYPES = {
    "png": "image/png",
    "jpg": "image/jpeg",
    "jpeg": "image/jpeg",
    "webp": "image/webp",
    "avif": "image/avif",
}
PMTILES_FORMATS = {
    TileType.PNG: "png",
    TileType.JPEG: "jpg",
    TileType.WEBP: "webp",
    TileType.AVIF: "avif",
}


class TileSetError(Exception):
    """A file in the tiles folder that cannot be served, and why."""


class UnknownTileSet(LookupError):
    """No tile set of that name is installed."""


@dataclass(frozen=True)
class TileSetInfo:
    name: str
    kind: str  # "mbtiles" or "pmtiles"
    media_type: str
    min_zoom: int
    max_zoom: int
    # west, south, east, north in degrees, when the file says
    bounds: tuple[float, float, float, float] | None
    attribution: str
    # Changes whenever the file does, so a replaced set gets new tile URLs.
    version: str


class TileSource(Protocol):
    info: TileSetInfo

    def tile(self, z: int, x: int, y: int) -> bytes | None: ...

    def close(self) -> None: ...


def check_name(name: str) -> str:
    if not NAME_PATTERN.match(name):
        raise TileSetError(
            f"{name!r} is not a tile set name: letters, digits, '_', '.' and '-', "
            "at most 64, starting with a letter or digit"
        )
    return name


def flip_row(z: int, row: int) -> int:
    """An XYZ row (counted from the north) as a TMS row (from the south), or back."""
    height: int = WEB_MERCATOR.matrix(z).matrixHeight
    return height - 1 - row


def _version(path: Path) -> str:
    stat = path.stat()
    return hashlib.blake2s(f"{stat.st_size}:{stat.st_mtime_ns}".encode(), digest_size=6).hexdigest()


def _bounds(value: Any) -> tuple[float, float, float, float] | None:
    try:
        west, south, east, north = (float(part) for part in str(value).split(","))
    except ValueError:
        return None
    if not (-180 <= west < east <= 180 and -90 <= south < north <= 90):
        return None
    return west, south, east, north


class MBTilesSource:
    """An MBTiles file, opened read-only; one connection shared under a lock."""

    def __init__(self, path: Path, name: str) -> None:
        try:
            self._db = sqlite3.connect(f"file:{path}?mode=ro", uri=True, check_same_thread=False)
            metadata = dict(self._db.execute("SELECT name, value FROM metadata").fetchall())
            self._db.execute("SELECT 1 FROM tiles LIMIT 1").fetchall()
        except sqlite3.DatabaseError as error:
            raise TileSetError(f"{path.name} is not an MBTiles file: {error}") from error
        self._lock = threading.Lock()
        kind = str(metadata.get("format", "png")).lower()
        if kind not in MEDIA_TYPES:
            self._db.close()
            raise TileSetError(f"{path.name} holds {kind!r} tiles; only raster tiles are drawn")
        zooms = self._db.execute("SELECT MIN(zoom_level), MAX(zoom_level) FROM tiles").fetchone()
        min_zoom = int(metadata.get("minzoom", zooms[0] if zooms[0] is not None else 0))
        max_zoom = int(metadata.get("maxzoom", zooms[1] if zooms[1] is not None else 0))
        self.info = TileSetInfo(
            name=name,
            kind="mbtiles",
            media_type=MEDIA_TYPES[kind],
            min_zoom=min_zoom,
            max_zoom=max_zoom,
            bounds=_bounds(metadata.get("bounds")) or self._extent(max_zoom),
            attribution=str(metadata.get("attribution", "")),
            version=_version(path),
        )

    def _extent(self, zoom: int) -> tuple[float, float, float, float] | None:
        """The bounds of the tiles themselves, for a file whose metadata gives none."""
        row = self._db.execute(
            "SELECT MIN(tile_column), MAX(tile_column), MIN(tile_row), MAX(tile_row)"
            " FROM tiles WHERE zoom_level = ?",
            (zoom,),
        ).fetchone()
        if row is None or row[0] is None:
            return None
        # TMS rows count up north: the highest is the northern edge
        north_west = WEB_MERCATOR.bounds(morecantile.Tile(row[0], flip_row(zoom, row[3]), zoom))
        south_east = WEB_MERCATOR.bounds(morecantile.Tile(row[1], flip_row(zoom, row[2]), zoom))
        return north_west.left, south_east.bottom, south_east.right, north_west.top

    def tile(self, z: int, x: int, y: int) -> bytes | None:
        tms_row = flip_row(z, y)  # MBTiles counts rows from the south (TMS)
        with self._lock:
            row = self._db.execute(
                "SELECT tile_data FROM tiles WHERE zoom_level=? AND tile_column=? AND tile_row=?",
                (z, x, tms_row),
            ).fetchone()
        return bytes(row[0]) if row else None

    def close(self) -> None:
        with self._lock:
            self._db.close()


class PMTilesSource:
    """A PMTiles (v3) file, memory-mapped; reads are lock-free."""

    def __init__(self, path: Path, name: str) -> None:
        self._file = path.open("rb")
        try:
            self._map = mmap.mmap(self._file.fileno(), 0, access=mmap.ACCESS_READ)
            self._reader = PMTilesReader(self._get_bytes)
            header = self._reader.header()
            metadata = self._reader.metadata()
        except Exception as error:  # a truncated or foreign file fails in many ways
            self._file.close()
            raise TileSetError(f"{path.name} is not a PMTiles v3 file: {error}") from error
        kind = PMTILES_FORMATS.get(header["tile_type"])
        if kind is None:
            self.close()
            raise TileSetError(
                f"{path.name} holds {header['tile_type'].name} tiles; only raster tiles are drawn"
            )
        self._gzip = header["tile_compression"] == Compression.GZIP
        bounds = (
            header["min_lon_e7"] / 1e7,
            header["min_lat_e7"] / 1e7,
            header["max_lon_e7"] / 1e7,
            header["max_lat_e7"] / 1e7,
        )
        self.info = TileSetInfo(
            name=name,
            kind="pmtiles",
            media_type=MEDIA_TYPES[kind],
            min_zoom=int(header["min_zoom"]),
            max_zoom=int(header["max_zoom"]),
            bounds=_bounds(",".join(map(str, bounds))),
            attribution=str(metadata.get("attribution", "")) if isinstance(metadata, dict) else "",
            version=_version(path),
        )

    def _get_bytes(self, offset: int, length: int) -> bytes:
        return self._map[offset : offset + length]

    def tile(self, z: int, x: int, y: int) -> bytes | None:
        data = self._reader.get(z, x, y)
        if data is None:
            return None
        return gzip.decompress(data) if self._gzip else bytes(data)

    def close(self) -> None:
        if hasattr(self, "_map"):
            self._map.close()
        self._file.close()


def open_tile_set(path: Path) -> TileSource:
    name = check_name(path.stem)
    if path.suffix == ".mbtiles":
        return MBTilesSource(path, name)
    if path.suffix == ".pmtiles":
        return PMTilesSource(path, name)
    raise TileSetError(f"{path.name}: a tile set is a .mbtiles or a .pmtiles file")


class TileLibrary:
    """The tile sets in one folder, opened once and reopened when their file changes."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self._lock = threading.Lock()
        # path -> (size and mtime it was opened at, the source)
        self._open: dict[Path, tuple[tuple[int, int], TileSource]] = {}
        self._refused: dict[Path, tuple[int, int]] = {}  # logged once per file version
        self._scanned_at = -RESCAN_S

    def sets(self) -> list[TileSetInfo]:
        """Every set that can be served, by name."""
        with self._lock:
            self._rescan()
            return sorted((source.info for _, source in self._open.values()), key=_by_name)

    def tile(self, name: str, z: int, x: int, y: int) -> tuple[TileSetInfo, bytes | None]:
        """The set's description and the tile (None where the set has none)."""
        with self._lock:
            # A tile read looks at the folder at most once a second (a view asks for ~20).
            if time.monotonic() - self._scanned_at > RESCAN_S:
                self._rescan()
            source = next((s for _, s in self._open.values() if s.info.name == name), None)
            if source is None:
                raise UnknownTileSet(name)
            # Read under the lock: a rescan may close a replaced file's source.
            return source.info, source.tile(z, x, y)

    def close(self) -> None:
        with self._lock:
            for _, source in self._open.values():
                source.close()
            self._open.clear()

    def _rescan(self) -> None:
        self._scanned_at = time.monotonic()
        present: dict[Path, tuple[int, int]] = {}
        if self.folder.is_dir():
            for path in self.folder.iterdir():
                if path.suffix in SUFFIXES and path.is_file():
                    stat = path.stat()
                    present[path] = (stat.st_size, stat.st_mtime_ns)
        for path in list(self._open):
            if present.get(path) != self._open[path][0]:
                self._open.pop(path)[1].close()
        for path, stamp in present.items():
            if path in self._open or self._refused.get(path) == stamp:
                continue
            try:
                self._open[path] = (stamp, open_tile_set(path))
                log.info("tile set %s: %s", path.stem, path)
            except (TileSetError, OSError) as error:
                self._refused[path] = stamp
                log.warning("tile set not served: %s", error)


def _by_name(info: TileSetInfo) -> str:
    return info.name
