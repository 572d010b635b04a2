"""One survey's mosaic on disk: its tiles, the blending state behind them, and versions.

Layout under ``<data dir>/mosaics/<survey id>/``:
- ``tiles/{z}/{x}/{y}.raw``: a tile's working state, uncompressed: its pixels (BGRA,
  transparent where no photo lies) and, per pixel, the distance from the nadir of the
  photo that won it (uint16, quarter pixels; the largest value means none): what the next
  photo's pixels are compared with.
- ``mosaic.json``: the zoom range, each tile's version, and the revision (photos applied).

The state is raw rather than PNG because encoding is the slow part (a 256 px PNG takes
longer than blending it), and a tile is rewritten by every photo that overlaps it: tiles
are encoded when asked for (``encode``), once per version.

The tiles being worked on stay in memory (an LRU of ``cache_tiles``): with the survey's
overlaps, the next photo lands mostly on the same tiles, so a tile is written to disk when
it leaves the cache or at ``flush`` (the service flushes whenever its queue runs dry),
not after every photo. Readers see the cache first, so a new tile is visible at once.

Every file is written to a temporary name and renamed over the old one, so a reader (the
tile route, an export) sees the previous tile or the new one, never half of one. Only one
writer works on a survey at a time (MosaicService holds the survey's lock); the cache has
its own lock for the readers, and its arrays are replaced, never changed in place.
"""

from __future__ import annotations

import json
import os
import tempfile
import threading
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from backend.imagery.mosaic.georef import TILE_PX, pixel_to_lonlat
from common.opencv import cv2

Rgba = npt.NDArray[np.uint8]
Distances = npt.NDArray[np.float32]
TileKey = tuple[int, int, int]  # z, x, y


@dataclass(frozen=True)
class TileSpan:
    """The block of one zoom's tiles that some keys cover: columns ``x0`` to ``x1 - 1``,
    rows ``y0`` to ``y1 - 1`` (what an export or an overview lays out as one image)."""

    zoom: int
    x0: int
    y0: int
    x1: int
    y1: int

    @classmethod
    def of(cls, zoom: int, keys: list[TileKey]) -> TileSpan:
        xs, ys = [k[1] for k in keys], [k[2] for k in keys]
        return cls(zoom, min(xs), min(ys), max(xs) + 1, max(ys) + 1)

    @property
    def width_px(self) -> int:
        return (self.x1 - self.x0) * TILE_PX

    @property
    def height_px(self) -> int:
        return (self.y1 - self.y0) * TILE_PX

    def offset_px(self, key: TileKey) -> tuple[int, int]:
        """Where ``key``'s tile starts in the span's image: left, top."""
        return (key[1] - self.x0) * TILE_PX, (key[2] - self.y0) * TILE_PX

    def bounds(self) -> tuple[float, float, float, float]:
        """west, south, east, north in degrees."""
        west, north = pixel_to_lonlat(self.zoom, self.x0 * TILE_PX, self.y0 * TILE_PX)
        east, south = pixel_to_lonlat(self.zoom, self.x1 * TILE_PX, self.y1 * TILE_PX)
        return west, south, east, north


PNG_LEVEL = 1  # photos barely shrink at higher levels, which take twice as long
JPEG_QUALITY = 90
PIXELS_BYTES = TILE_PX * TILE_PX * 4
DISTANCE_STEPS = 4.0  # per pixel
NO_DISTANCE = np.iinfo(np.uint16).max


def atomic_write(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "wb") as out:
            out.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


CACHE_TILES = 384  # 512 KB each, about 200 MB: the tiles a few 12 MP photos cover


@dataclass
class TileStore:
    folder: Path
    cache_tiles: int = CACHE_TILES
    min_zoom: int | None = None
    max_zoom: int | None = None
    revision: int = 0
    versions: dict[TileKey, int] = field(default_factory=dict)
    # Decoded, so a photo that lands on a tile just written reads it for nothing.
    _cache: OrderedDict[TileKey, tuple[Rgba, Distances]] = field(default_factory=OrderedDict)
    _dirty: set[TileKey] = field(default_factory=set)
    _lock: threading.Lock = field(default_factory=threading.Lock)

    @classmethod
    def open(cls, folder: Path, cache_tiles: int = CACHE_TILES) -> TileStore:
        store = cls(folder, cache_tiles)
        index = folder / "mosaic.json"
        if index.is_file():
            saved = json.loads(index.read_text())
            store.min_zoom, store.max_zoom = saved["min_zoom"], saved["max_zoom"]
            store.revision = int(saved["revision"])
            store.versions = {
                (int(z), int(x), int(y)): int(v)
                for key, v in saved["versions"].items()
                for z, x, y in [key.split("/")]
            }
        return store

    def save_index(self) -> None:
        index = {
            "min_zoom": self.min_zoom,
            "max_zoom": self.max_zoom,
            "revision": self.revision,
            "versions": {f"{z}/{x}/{y}": v for (z, x, y), v in self.versions.items()},
        }
        atomic_write(self.folder / "mosaic.json", json.dumps(index).encode())

    def tile_path(self, key: TileKey) -> Path:
        z, x, y = key
        return self.folder / "tiles" / str(z) / str(x) / f"{y}.raw"

    def read(self, key: TileKey) -> tuple[Rgba, Distances] | None:
        """A tile's pixels (BGRA) and nadir distances (inf: no photo's own), or None
        where it has none yet."""
        if key not in self.versions:
            return None
        with self._lock:
            cached = self._cache.get(key)
            if cached is not None:
                self._cache.move_to_end(key)
                return cached  # never changed in place: writes replace the pair
        try:
            data = self.tile_path(key).read_bytes()
        except FileNotFoundError:
            return None
        if len(data) != PIXELS_BYTES * 3 // 2:
            return None  # a damaged tile is rebuilt from the photos that follow
        rgba = np.frombuffer(data, np.uint8, PIXELS_BYTES).reshape(TILE_PX, TILE_PX, 4).copy()
        steps = np.frombuffer(data, np.uint16, offset=PIXELS_BYTES).reshape(TILE_PX, TILE_PX)
        distances = steps.astype(np.float32) / DISTANCE_STEPS
        distances[steps == NO_DISTANCE] = np.inf
        return rgba, distances

    def write(self, key: TileKey, rgba: Rgba, distances: Distances) -> None:
        if rgba.base is not None:
            rgba = rgba.copy()  # a view would keep a whole warped canvas alive
        evicted: list[tuple[TileKey, tuple[Rgba, Distances]]] = []
        with self._lock:
            self._cache[key] = (rgba, distances)
            self._cache.move_to_end(key)
            self._dirty.add(key)
            self.versions[key] = self.versions.get(key, 0) + 1
            while len(self._cache) > self.cache_tiles:
                old, data = self._cache.popitem(last=False)
                if old in self._dirty:
                    self._dirty.discard(old)
                    evicted.append((old, data))
        for old, state in evicted:
            atomic_write(self.tile_path(old), _raw(*state))

    def flush(self) -> None:
        """Every tile changed in memory to disk, then the index that counts them."""
        with self._lock:
            dirty = [(key, self._cache[key]) for key in self._dirty]
            self._dirty.clear()
        for key, state in dirty:
            atomic_write(self.tile_path(key), _raw(*state))
        self.save_index()

    def pixels(self, key: TileKey) -> Rgba | None:
        state = self.read(key)
        return None if state is None else state[0]

    def encode(self, key: TileKey, *, always_png: bool = False) -> tuple[bytes, str] | None:
        """The tile as served, and its media type: JPEG where every pixel is covered
        (a fifth of the PNG's size, 20 times faster to encode), PNG where some are
        transparent; always PNG for exports, whose tile format is one for the set."""
        rgba = self.pixels(key)
        if rgba is None:
            return None
        if not always_png and bool((rgba[:, :, 3] == 255).all()):
            ok, data = cv2.imencode(
                ".jpg", rgba[:, :, :3], [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY]
            )
            media_type = "image/jpeg"
        else:
            ok, data = cv2.imencode(".png", rgba, [cv2.IMWRITE_PNG_COMPRESSION, PNG_LEVEL])
            media_type = "image/png"
        if not ok:
            raise OSError(f"could not encode tile {key}")
        return data.tobytes(), media_type

    def keys(self, zoom: int) -> Iterator[TileKey]:
        return (key for key in list(self.versions) if key[0] == zoom)


def _raw(rgba: Rgba, distances: Distances) -> bytes:
    """A tile's state as its file holds it (see the module's docstring)."""
    steps = np.minimum(distances * DISTANCE_STEPS, NO_DISTANCE - 1)
    steps = np.where(np.isfinite(distances), steps, NO_DISTANCE).astype(np.uint16)
    return rgba.tobytes() + steps.tobytes()
