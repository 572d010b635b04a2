"""The mosaic's seams at zoom 22 near longitude 0, where a global pixel number is about
5.4e8 and float32 steps by 64 px: two overlapping photos (one red, one blue) are blended
and, row by row, the seam (where the blend is half each) lies within 2 px of the true
nearest-nadir line, the perpendicular bisector of the two nadirs computed in float64, and
the feather across it is a ramp, not a step (issue #35)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import numpy.typing as npt

from backend.imagery.mosaic.engine import EDGE_RAMP_PX, FEATHER_PX, apply_photo, with_edge_ramp
from backend.imagery.mosaic.georef import TILE_PX, Footprint, footprint
from backend.imagery.mosaic.store import TileStore
from protocol.photos import CameraIntrinsics, PhotoPose

ZOOM = 22
CAMERA = CameraIntrinsics(
    sensor_width_mm=13.2,
    sensor_height_mm=8.8,
    image_width_px=480,
    image_height_px=360,
    focal_length_mm=8.8,
)
ALTITUDE_M = 10.0  # 3.1 cm/px: zoom 22's 3.7 cm pixels at the equator; 15 x 11 m footprints
LAT, LON = 0.0002, 0.00003  # a few metres east of longitude 0
M_PER_DEG = 111_320.0


def _pose(east_m: float, north_m: float) -> PhotoPose:
    return PhotoPose(
        lat=LAT + north_m / M_PER_DEG,
        lon=LON + east_m / (M_PER_DEG * math.cos(math.radians(LAT))),
        alt_msl=ALTITUDE_M,
        alt_rel=ALTITUDE_M,
        roll=0.0,
        pitch=0.0,
        yaw=0.0,
        time=0.0,
    )


def _solid(bgr: tuple[int, int, int]) -> npt.NDArray[np.uint8]:
    image = np.empty((CAMERA.image_height_px, CAMERA.image_width_px, 3), np.uint8)
    image[:] = bgr
    return with_edge_ramp(image)


def _tiles(
    store: TileStore, keys: set[tuple[int, int, int]]
) -> tuple[npt.NDArray[np.uint8], int, int]:
    """The tiles stitched into one image, and its top-left global pixel."""
    xs = [x for _, x, _ in keys]
    ys = [y for _, _, y in keys]
    x0, y0 = min(xs), min(ys)
    image = np.zeros(((max(ys) - y0 + 1) * TILE_PX, (max(xs) - x0 + 1) * TILE_PX, 4), np.uint8)
    for z, x, y in keys:
        pixels = store.pixels((z, x, y))
        assert pixels is not None
        top, left = (y - y0) * TILE_PX, (x - x0) * TILE_PX
        image[top : top + TILE_PX, left : left + TILE_PX] = pixels
    return image, x0 * TILE_PX, y0 * TILE_PX


def _inner(place: Footprint, margin: float) -> tuple[float, float, float, float]:
    x0, y0, x1, y1 = place.bounds_px(ZOOM)
    return x0 + margin, y0 + margin, x1 - margin, y1 - margin


def test_the_seam_follows_the_nearest_nadir_line_at_zoom_22_near_longitude_0(
    tmp_path: Path,
) -> None:
    store = TileStore.open(tmp_path)
    store.min_zoom = store.max_zoom = ZOOM
    # B is 4 m east and 2.5 m north of A: a slanted seam, crossing many pixel rows.
    first, second = footprint(_pose(0, 0), CAMERA), footprint(_pose(4, 2.5), CAMERA)
    keys = set(apply_photo(store, _solid((0, 0, 255)), first).tiles)  # red
    keys |= set(apply_photo(store, _solid((255, 0, 0)), second).tiles)  # blue
    image, left, top = _tiles(store, keys)
    blue = image[:, :, 0].astype(np.float64)
    ax, ay = first.nadir_px(ZOOM)
    bx, by = second.nadir_px(ZOOM)
    assert ax > 5e8  # float32 steps by 64 px here
    # Where both photos are whole (away from their edge ramps and the feather).
    margin = EDGE_RAMP_PX + 2 * FEATHER_PX
    a, b = _inner(first, margin), _inner(second, margin)
    both = (max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3]))
    errors = []
    widths = []
    for row in range(math.ceil(both[1]), math.floor(both[3])):
        y = row + 0.5  # the pixel's centre in global pixels
        # Equidistant from both nadirs: |p - A|^2 = |p - B|^2, solved for x on this row.
        truth = ((bx**2 - ax**2) + (by**2 - ay**2) - 2 * y * (by - ay)) / (2 * (bx - ax))
        if not both[0] <= truth <= both[2]:
            continue
        line = blue[row - top, math.floor(both[0]) - left : math.ceil(both[2]) - left]
        start = math.floor(both[0])
        # The first column at least half blue (B lies east), between it and the one before.
        c = int(np.argmax(line >= 127.5))
        assert c > 0, "the row starts blue"
        assert line[c - 1] < 127.5 <= line[c]
        crossing = start + c - 1 + 0.5 + (127.5 - line[c - 1]) / (line[c] - line[c - 1])
        errors.append(abs(crossing - truth))
        # The feather: the pixels neither photo's alone, on a ramp 2 x FEATHER_PX wide
        # along the distance difference (wider across the seam on a slanted row).
        widths.append(int(((line > 12) & (line < 243)).sum()))
    assert len(errors) > 100  # the seam crosses this many rows
    print(f"\nseam vs the nearest-nadir line over {len(errors)} rows: worst {max(errors):.2f} px")
    assert max(errors) <= 2.0
    assert min(widths) >= FEATHER_PX, "the feather is a step somewhere"
