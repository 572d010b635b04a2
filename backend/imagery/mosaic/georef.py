"""Direct georeferencing: where a photo lies on the ground, from its pose and camera alone.

The ground is a horizontal plane at the site's elevation: the camera's height above it is
the pose's ``alt_rel`` (its height above home, and home is on the site's ground). A grid of
image points (corners included) goes through common/camera_geometry.py's pixel-to-ground
homography to east/north metres from the nadir, then to latitude/longitude (pymap3d's
east-north-up on WGS84, as common/geodesy.py, dropped onto the surface), then to
web-mercator metres (EPSG:3857, the tile grid of morecantile's WebMercatorQuad). A
homography fitted to those points maps the photo onto the mercator plane: the map is a true
projective one up to the mercator's change of scale across the footprint (parts per
million over a hundred metres), so the fit's residual is far below a pixel, and one
cv2.warpPerspective per zoom puts the photo into the tile grid.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import Final

import morecantile
import numpy as np
import numpy.typing as npt
from pymap3d.enu import enu2geodetic
from pyproj import Proj, Transformer

from common.camera_geometry import camera_to_enu, gsd_m, image_to_ground
from common.geodesy import EARTH_MEAN_RADIUS_M, WGS84
from common.opencv import cv2
from protocol.photos import CameraIntrinsics, PhotoPose

Homography = npt.NDArray[np.float64]
Floats = npt.NDArray[np.float64]
TMS: Final = morecantile.tms.get("WebMercatorQuad")
TILE_PX: Final = 256
# The web-mercator world's width in metres (2 pi R on the sphere of radius a).
WORLD_M: Final = 2 * 20037508.342789244
MAX_TILT_DEG: Final = 30.0  # beyond this the corners near the horizon smear over the map
MIN_HEIGHT_M: Final = 1.0
UPSAMPLE: Final = 1.1  # a zoom whose pixels are 10 % finer than the photo's still counts
MAX_ZOOM: Final = 26  # 2 mm pixels at the equator
GRID: Final = 5  # image points a side that the mercator homography is fitted to


# pyproj's objects are not to be shared between threads; the mosaic's worker and its
# blending pool each get their own.
_PROJ = threading.local()


def _projections() -> tuple[Transformer, Proj]:
    if not hasattr(_PROJ, "pair"):
        _PROJ.pair = (
            Transformer.from_crs("EPSG:4326", "EPSG:3857", always_xy=True),
            Proj("EPSG:3857"),
        )
    pair: tuple[Transformer, Proj] = _PROJ.pair
    return pair


def to_mercator(lon: Floats, lat: Floats) -> tuple[Floats, Floats]:
    """EPSG:3857 metres of longitudes and latitudes in degrees (pyproj, vectorised;
    morecantile's TMS.xy gives the same one point at a time, far slower)."""
    x, y = _projections()[0].transform(lon, lat)
    return np.asarray(x, np.float64), np.asarray(y, np.float64)


class GeorefError(ValueError):
    """A photo that cannot be put on the ground; the message says why."""


@dataclass(frozen=True)
class Footprint:
    """A photo on the mercator plane: the homography from its pixels to mercator metres
    relative to its nadir, the nadir in mercator metres, and the ground corners."""

    to_mercator: Homography  # photo (u, v, 1) -> (mx - nadir_mx, my - nadir_my, w)
    nadir_m: tuple[float, float]
    corners_lonlat: list[tuple[float, float]]  # top-left, top-right, bottom-right, bottom-left
    corners_m: Floats  # the same in mercator metres, 4 x 2
    gsd_m: float

    def to_pixels(self, zoom: int, origin_px: tuple[int, int]) -> Homography:
        """Photo pixels to the pixels of a canvas whose top-left pixel is ``origin_px`` of
        the zoom's global grid. Pixel centres are at integers in both (OpenCV's
        convention); a global pixel i covers [i, i + 1), hence the half pixel."""
        scale = TILE_PX * 2**zoom / WORLD_M
        nadir_x = (self.nadir_m[0] + WORLD_M / 2) * scale
        nadir_y = (WORLD_M / 2 - self.nadir_m[1]) * scale
        affine = np.array(
            [
                [scale, 0.0, nadir_x - origin_px[0] - 0.5],
                [0.0, -scale, nadir_y - origin_px[1] - 0.5],
                [0.0, 0.0, 1.0],
            ]
        )
        result: Homography = affine @ self.to_mercator
        return result

    def nadir_px(self, zoom: int) -> tuple[float, float]:
        scale = TILE_PX * 2**zoom / WORLD_M
        return (self.nadir_m[0] + WORLD_M / 2) * scale, (WORLD_M / 2 - self.nadir_m[1]) * scale

    def bounds_px(self, zoom: int) -> tuple[float, float, float, float]:
        """min x, min y, max x, max y of the corners in the zoom's global pixels."""
        scale = TILE_PX * 2**zoom / WORLD_M
        xs = (self.corners_m[:, 0] + WORLD_M / 2) * scale
        ys = (WORLD_M / 2 - self.corners_m[:, 1]) * scale
        return float(xs.min()), float(ys.min()), float(xs.max()), float(ys.max())


def tilt_deg(pose: PhotoPose) -> float:
    """The angle between the lens's axis and the vertical."""
    axis_up = camera_to_enu(pose)[2][2]  # the up component of the camera's z axis
    return math.degrees(math.acos(max(-1.0, min(1.0, -axis_up))))


def native_zoom(gsd: float, lat: float) -> int:
    """The finest zoom whose tile pixels are no finer on the ground than the photo's GSD
    (within UPSAMPLE): a finer one would only interpolate, at up to four times the pixels
    to warp, blend and store."""
    # A mercator pixel covers less ground away from the equator, by the projection's scale.
    scale = _projections()[1].get_factors(0.0, lat).parallel_scale
    metres_per_px_z0 = WORLD_M / scale / TILE_PX
    return max(0, min(MAX_ZOOM, math.floor(math.log2(UPSAMPLE * metres_per_px_z0 / gsd))))


def footprint(pose: PhotoPose, camera: CameraIntrinsics) -> Footprint:
    """The photo on the ground, or GeorefError when it cannot be placed."""
    height = pose.alt_rel
    if height < MIN_HEIGHT_M:
        raise GeorefError(
            f"the camera was {height:.1f} m above home; a photo for the map needs at least "
            f"{MIN_HEIGHT_M:g} m"
        )
    tilt = tilt_deg(pose)
    if tilt > MAX_TILT_DEG:
        raise GeorefError(
            f"the camera was tilted {tilt:.0f} degrees from the vertical (roll {pose.roll:g}, "
            f"pitch {pose.pitch:g}); the map takes photos within {MAX_TILT_DEG:g} degrees"
        )
    ground = np.array(image_to_ground(pose, camera, height))
    width, height_px = camera.image_width_px, camera.image_height_px
    us, vs = np.meshgrid(np.linspace(0, width - 1, GRID), np.linspace(0, height_px - 1, GRID))
    pixels = np.stack([us.ravel(), vs.ravel(), np.ones(us.size)])
    en = ground @ pixels
    east, north = en[0] / en[2], en[1] / en[2]
    # Off the tangent plane down onto the surface by the sphere's drop, d^2 / 2R (about
    # a millimetre 100 m out), as LocalFrame.to_geo does, all points at once.
    drop = -(east**2 + north**2) / (2 * EARTH_MEAN_RADIUS_M)
    lat, lon, _ = enu2geodetic(east, north, drop, pose.lat, pose.lon, 0.0, WGS84)
    mx, my = to_mercator(np.asarray(lon), np.asarray(lat))
    nadir_x, nadir_y = to_mercator(np.array(pose.lon), np.array(pose.lat))
    nadir = (float(nadir_x), float(nadir_y))
    merc = np.stack([mx - nadir[0], my - nadir[1]], axis=1)
    fitted, _ = cv2.findHomography(pixels[:2].T.copy(), merc, 0)
    if fitted is None:
        raise GeorefError("the photo's ground points do not fit a plane view")
    last = GRID * GRID - 1
    corner_index = [0, GRID - 1, last, last - GRID + 1]
    return Footprint(
        to_mercator=np.asarray(fitted, np.float64),
        nadir_m=nadir,
        corners_lonlat=[(float(lon[i]), float(lat[i])) for i in corner_index],
        corners_m=np.stack([mx[corner_index], my[corner_index]], axis=1),
        gsd_m=gsd_m(camera, height),
    )


def pixel_to_lonlat(zoom: int, x: float, y: float) -> tuple[float, float]:
    """Longitude and latitude of a point in the zoom's global pixel grid (pixel centres at
    integer + 0.5, as a tile's pixel (0, 0) covers [0, 1))."""
    scale = TILE_PX * 2**zoom / WORLD_M
    mx = x / scale - WORLD_M / 2
    my = WORLD_M / 2 - y / scale
    lon, lat = TMS.lnglat(mx, my)
    return lon, lat
