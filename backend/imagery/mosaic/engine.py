"""Putting one photo into a survey's tiles: warp, blend, write (synchronous; the service
runs it in a worker thread).

For each zoom from the survey's native one down to its overviews, the photo (halved as
often as the zoom is below the native one) is warped with one cv2.warpPerspective onto a
canvas aligned with the tile grid, then cut into tiles and blended into what they hold:

- Nearest nadir wins: each tile pixel remembers how far (in pixels) it lies from the nadir
  of the photo that painted it (measured from the tile's corner, so float32 holds it to a
  fraction of a pixel at every zoom); a new photo takes the pixels it sees from nearer, so the
  mosaic is made of each photo's least tilted, least distorted middle.
- Feathered seams: the take-over is a linear ramp of the difference of the two
  distances (2 x FEATHER_PX wide), and a photo's own edges fade in over EDGE_RAMP_PX, so
  neither a seam nor a photo's border shows as a hard line.
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from backend.imagery.mosaic.georef import TILE_PX, Footprint
from backend.imagery.mosaic.store import Rgba, TileKey, TileStore
from common.opencv import cv2

FEATHER_PX = 6.0
EDGE_RAMP_PX = 8
# A pixel painted at least this opaquely by a photo counts as that photo's for the
# nearest-nadir rule; in the faded edge it stays open to the next photo.
OWNED_ALPHA = 250
MAX_CANVAS_PX = 64_000_000  # a sanity bound: a 12 MP photo's canvas is about 20 MP
TILE_WORKERS = ThreadPoolExecutor(min(4, os.cpu_count() or 1), thread_name_prefix="mosaic-tile")


class PhotoError(ValueError):
    """A photo whose pixels cannot be used; the message says why."""


@dataclass(frozen=True)
class Applied:
    tiles: list[TileKey]


def decode(data: bytes, width: int, height: int) -> Rgba:
    """The JPEG as BGRA with the edge ramp in alpha, or PhotoError."""
    image: npt.NDArray[np.uint8] | None = cv2.imdecode(  # type: ignore[assignment]
        np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR
    )
    if image is None:
        raise PhotoError("the image is not a readable JPEG (corrupt or truncated)")
    if image.shape[:2] != (height, width):
        raise PhotoError(
            f"the image is {image.shape[1]} x {image.shape[0]} px but its camera model says "
            f"{width} x {height}"
        )
    return with_edge_ramp(image)


def with_edge_ramp(bgr: npt.NDArray[np.uint8]) -> Rgba:
    """BGRA, opaque inside, its alpha falling to 255 / EDGE_RAMP_PX at the outermost
    pixels: only the border strips are touched (a 12 MP frame is mostly inside)."""
    bgra: Rgba = cv2.cvtColor(bgr, cv2.COLOR_BGR2BGRA)  # type: ignore[assignment]
    height, width = bgr.shape[:2]
    band = min(EDGE_RAMP_PX, height // 2, width // 2)
    steps = ((np.arange(band) + 1) * (255.0 / EDGE_RAMP_PX)).astype(np.uint8)
    alpha = bgra[:, :, 3]
    for i in range(band):
        # From the outside in, each ring no more opaque than the one inside it.
        for edge in (alpha[i, i : width - i], alpha[height - 1 - i, i : width - i]):
            np.minimum(edge, steps[i], out=edge)
        for edge in (alpha[i : height - i, i], alpha[i : height - i, width - 1 - i]):
            np.minimum(edge, steps[i], out=edge)
    return bgra


def _halve(photo: Rgba) -> Rgba:
    height, width = photo.shape[:2]
    size = (max(1, width // 2), max(1, height // 2))
    half: Rgba = cv2.resize(photo, size, interpolation=cv2.INTER_AREA)  # type: ignore[assignment]
    return half


def apply_photo(store: TileStore, photo: Rgba, place: Footprint) -> Applied:
    """Blend the photo (BGRA, full size) into every zoom of the store."""
    assert store.max_zoom is not None
    assert store.min_zoom is not None
    written: list[TileKey] = []
    level = photo
    full_w = photo.shape[1]
    for zoom in range(store.max_zoom, store.min_zoom - 1, -1):
        scale = full_w / level.shape[1]  # the level's pixel in full-size photo pixels
        written += _apply_zoom(store, level, scale, place, zoom)
        # The next zoom's pixels are twice the size: halve the photo while it is finer.
        if level.shape[1] > 64:
            level = _halve(level)
    return Applied(written)


def _apply_zoom(
    store: TileStore, photo: Rgba, scale: float, place: Footprint, zoom: int
) -> list[TileKey]:
    x0, y0, x1, y1 = place.bounds_px(zoom)
    tx0, ty0 = math.floor(x0 / TILE_PX), math.floor(y0 / TILE_PX)
    tx1, ty1 = math.floor(x1 / TILE_PX), math.floor(y1 / TILE_PX)
    width, height = (tx1 - tx0 + 1) * TILE_PX, (ty1 - ty0 + 1) * TILE_PX
    if width * height > MAX_CANVAS_PX:
        raise PhotoError(f"the photo covers {width * height} map pixels at zoom {zoom}")
    origin = (tx0 * TILE_PX, ty0 * TILE_PX)
    # The level's pixel (u', v') is the full photo's ((u' + 0.5) * scale - 0.5, ...).
    from_level = np.array([[scale, 0, 0.5 * scale - 0.5], [0, scale, 0.5 * scale - 0.5], [0, 0, 1]])
    to_canvas = place.to_pixels(zoom, origin) @ from_level
    canvas: Rgba = cv2.warpPerspective(  # type: ignore[assignment]
        photo,
        to_canvas,
        (width, height),
        flags=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=(0, 0, 0, 0),
    )
    nadir_x, nadir_y = place.nadir_px(zoom)
    cols = np.arange(TILE_PX, dtype=np.float32)

    def tile(tx: int, ty: int) -> TileKey | None:
        top, left = (ty - ty0) * TILE_PX, (tx - tx0) * TILE_PX
        piece = canvas[top : top + TILE_PX, left : left + TILE_PX]
        if not piece[:, :, 3].any():
            return None
        # The tile's offset from the nadir in float64 first, then per pixel in float32: a
        # global pixel number near zoom 22 is up to 1.1e9, where float32 steps by 64 px
        # (the seams were staircases of such blocks); the offsets are a few thousand px.
        dx = (cols + np.float32(tx * TILE_PX + 0.5 - nadir_x))[None, :]
        dy = (cols + np.float32(ty * TILE_PX + 0.5 - nadir_y))[:, None]
        distances = np.sqrt(dx * dx + dy * dy)
        key = (zoom, tx, ty)
        blended = _blend(store.read(key), piece, distances)
        if blended is None:
            return None
        store.write(key, *blended)
        return key

    # Each tile is its own: they are blended on all cores (numpy and OpenCV let go of the
    # GIL on whole arrays), which only ever touch different keys of the store.
    spots = [(tx, ty) for ty in range(ty0, ty1 + 1) for tx in range(tx0, tx1 + 1)]
    done = TILE_WORKERS.map(lambda spot: tile(*spot), spots)
    return [key for key in done if key is not None]


def _blend(
    old: tuple[Rgba, npt.NDArray[np.float32]] | None,
    new: Rgba,
    distances: npt.NDArray[np.float32],
) -> tuple[Rgba, npt.NDArray[np.float32]] | None:
    """The tile with the new photo's piece blended in, and its nadir distances; None when
    the photo wins no pixel of it (the tile stays as it is)."""
    alpha_new = new[:, :, 3]
    whole = bool(alpha_new.min() == 255)  # the photo covers the whole tile: most tiles
    if old is None:
        if whole:
            return new, distances
        owned = alpha_new >= OWNED_ALPHA
        return new, np.where(owned, distances, np.float32(np.inf)).astype(np.float32)
    old_rgba, old_nearest = old
    # The take-over: 1 where the new photo's nadir is FEATHER_PX nearer, 0 where it is
    # FEATHER_PX farther, linear between (inf - d is inf: an empty pixel is taken whole).
    weight = old_nearest - distances
    weight *= np.float32(0.5 / FEATHER_PX)
    weight += np.float32(0.5)
    np.clip(weight, 0.0, 1.0, out=weight)
    if whole:
        nearest = np.minimum(old_nearest, distances)
    else:
        weight *= alpha_new.astype(np.float32) * np.float32(1 / 255)
        owned = alpha_new >= OWNED_ALPHA
        nearest = np.where(owned, np.minimum(old_nearest, distances), old_nearest)
    if not weight.any():
        return None
    old_alpha = old_rgba[:, :, 3]
    if bool((old_alpha == 255).all()):
        # The common case inside the mosaic: opaque under opaque, one vectorised blend of
        # all four channels (the alpha is set to 255 after: opaque under anything stays
        # opaque; the new alpha is in the weight already): three times faster than
        # blending the colour channels' strided views, which OpenCV copies first.
        blended: Rgba = cv2.blendLinear(new, old_rgba, weight, 1.0 - weight)  # type: ignore[assignment]
        blended[:, :, 3] = 255  # whatever the rounding of w + (1 - w)
        return blended, nearest
    rgba = np.empty_like(old_rgba)
    # "Over" with the old tile's transparency (non-premultiplied colours).
    w = weight[:, :, None]
    below = (1.0 - w) * (old_alpha[:, :, None].astype(np.float32) * np.float32(1 / 255))
    alpha = w + below
    safe = np.where(alpha > 0, alpha, 1.0)
    colour = (w * new[:, :, :3] + below * old_rgba[:, :, :3]) / safe
    rgba[:, :, :3] = np.clip(colour + 0.5, 0, 255).astype(np.uint8)
    rgba[:, :, 3] = np.clip(alpha[:, :, 0] * 255.0 + 0.5, 0, 255).astype(np.uint8)
    return rgba, nearest
