"""The camera model: ground sample distance, altitude, footprint, lane spacing and trigger
distance, with QGroundControl's definitions (src/MissionManager/CameraCalc.cc,
`_recalcTriggerDistance`), so a QGC user gets the same numbers for the same camera:

- GSD (cm/px) = altitude * sensor_width * 100 / (image_width * focal_length), and back;
  QGC takes the sensor's width for both axes (square pixels).
- landscape: footprint across the lanes = image_width * GSD, along them = image_height * GSD;
  portrait swaps the two.
- lane spacing = side footprint * (100 - side overlap) / 100;
  trigger distance = frontal footprint * (100 - front overlap) / 100.

QGC's manual camera ("Manual (no camera specs)") has no sensor: the lane spacing and trigger
distance are given as they are (`manual`), and no GSD, footprint or overlap is known.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

from pydantic import ValidationError

from common.camera_geometry import gsd_m, height_for_gsd_m
from protocol.photos import (
    CameraIntrinsics,
    describe_camera,
    format_camera_model,
    parse_camera_model,
)


class CameraError(ValueError):
    """Camera or overlap settings that no survey can be planned from; the message says what
    to change."""


class Camera(CameraIntrinsics):
    """A survey's camera: the pinhole camera its photos carry (protocol.photos, so the plan,
    the photos' checks, the mosaic and the agent read one model and one GSD formula,
    common/camera_geometry.py's), with a name, how it is mounted and how it triggers."""

    name: str
    landscape: bool = True
    # Cameras that cannot trigger on distance get DO_DIGICAM_CONTROL at each photo instead.
    distance_trigger: bool = True

    def gsd_cm(self, altitude_m: float) -> float:
        """Ground sample distance in cm per pixel at this height above the ground."""
        return gsd_m(self, altitude_m) * 100.0

    def altitude_m(self, gsd_cm: float) -> float:
        """The height above the ground that gives this ground sample distance."""
        return height_for_gsd_m(self, gsd_cm / 100.0)

    def with_figures(self, **changes: Any) -> Camera:
        """This camera with some of its figures changed, checked as camera_of checks."""
        return camera_of(**{**self.model_dump(), **changes})


def camera_of(**fields: Any) -> Camera:
    """A camera from its fields; a CameraError names the first that no camera can have."""
    try:
        return Camera.model_validate(fields)
    except ValidationError as error:
        first = error.errors()[0]
        field = ".".join(str(part) for part in first["loc"])
        said = first["msg"].removeprefix("Input should be ")
        raise CameraError(f"camera {field} must be {said}, got {first.get('input')}") from None


def _preset(
    name: str,
    sensor_mm: tuple[float, float],
    image_px: tuple[int, int],
    focal_length_mm: float,
    *,
    distance_trigger: bool = True,
) -> Camera:
    return camera_of(
        name=name,
        sensor_width_mm=sensor_mm[0],
        sensor_height_mm=sensor_mm[1],
        image_width_px=image_px[0],
        image_height_px=image_px[1],
        focal_length_mm=focal_length_mm,
        distance_trigger=distance_trigger,
    )


# Presets: figures from the makers' specification sheets (sensor size in mm, still image
# size in px, true focal length in mm). They match QGC's CameraMetaData list for the same
# cameras.
PRESETS: Final[dict[str, Camera]] = {
    # Sony a6000 with the 16 mm kit lens: APS-C 23.5 x 15.6 mm, 6000 x 4000 px.
    "sony_a6000_16mm": _preset("Sony a6000 16mm", (23.5, 15.6), (6000, 4000), 16.0),
    # DJI Phantom 4 Pro/Advanced FC6310: 1" 13.2 x 8.8 mm, 5472 x 3648 px, 8.8 mm.
    "dji_phantom4_pro": _preset("DJI Phantom 4 Pro", (13.2, 8.8), (5472, 3648), 8.8),
    # DJI Mavic 3 Enterprise wide: 4/3" 17.3 x 13.0 mm, 5280 x 3956 px, 12.29 mm.
    "dji_mavic3e_wide": _preset("DJI Mavic 3E wide", (17.3, 13.0), (5280, 3956), 12.29),
    # MicaSense RedEdge-MX: 4.8 x 3.6 mm, 1280 x 960 px, 5.4 mm (triggered per photo).
    "micasense_rededge_mx": _preset(
        "MicaSense RedEdge-MX", (4.8, 3.6), (1280, 960), 5.4, distance_trigger=False
    ),
}


# A camera the fleet carries, named by its figures (an agent's --camera-model after the
# prefix), so that the name alone says the camera: a survey stored with it, the photos'
# checks and the planning workers read it without asking which vehicle carried it.
FLEET_PREFIX: Final = "fleet:"


def fleet_preset_id(camera: CameraIntrinsics) -> str:
    """The preset name of a camera a vehicle carries: "fleet:6.3,4.7,1600,1200,4.5"."""
    return FLEET_PREFIX + format_camera_model(camera)


def preset(name: str) -> Camera:
    if name.startswith(FLEET_PREFIX):
        try:
            figures = parse_camera_model(name.removeprefix(FLEET_PREFIX))
        except ValueError as error:
            raise CameraError(f"camera preset {name!r}: {error}") from None
        return camera_of(name=describe_camera(figures), **figures.model_dump())
    try:
        return PRESETS[name]
    except KeyError:
        known = ", ".join(sorted(PRESETS))
        raise CameraError(f"unknown camera preset {name!r}; known presets: {known}") from None


@dataclass(frozen=True, slots=True)
class CameraCalc:
    """What a camera gives at a height and overlaps, in QGC's terms."""

    camera: Camera | None  # None: a manual camera (no sensor figures)
    altitude_m: float
    gsd_cm: float | None  # None: a manual camera
    footprint_side_m: float  # across the lanes
    footprint_frontal_m: float  # along the lanes
    side_overlap_pct: float
    front_overlap_pct: float
    lane_spacing_m: float  # QGC's AdjustedFootprintSide
    trigger_distance_m: float  # QGC's AdjustedFootprintFrontal
    # Cameras that cannot trigger on distance get DO_DIGICAM_CONTROL at each photo instead.
    distance_trigger: bool = True


def manual(
    *, altitude_m: float, lane_spacing_m: float, trigger_distance_m: float, distance_trigger: bool
) -> CameraCalc:
    """A manual camera's plan: the spacing and trigger distance as given. Its footprints are
    taken as the least that leaves no gap (0 % overlap, the spacing and trigger distance
    themselves), so the coverage figures say what the plan guarantees and no more."""
    for field, value in (
        ("altitude_m", altitude_m),
        ("lane_spacing_m", lane_spacing_m),
        ("trigger_distance_m", trigger_distance_m),
    ):
        if not value > 0:
            raise CameraError(f"{field} must be greater than 0, got {value}")
    return CameraCalc(
        camera=None,
        altitude_m=altitude_m,
        gsd_cm=None,
        footprint_side_m=lane_spacing_m,
        footprint_frontal_m=trigger_distance_m,
        side_overlap_pct=0.0,
        front_overlap_pct=0.0,
        lane_spacing_m=lane_spacing_m,
        trigger_distance_m=trigger_distance_m,
        distance_trigger=distance_trigger,
    )


def calculate(
    camera: Camera,
    *,
    altitude_m: float | None = None,
    gsd_cm: float | None = None,
    side_overlap_pct: float = 70.0,
    front_overlap_pct: float = 80.0,
) -> CameraCalc:
    """Give exactly one of altitude_m and gsd_cm; the other is computed."""
    if (altitude_m is None) == (gsd_cm is None):
        raise CameraError("give exactly one of altitude_m and gsd_cm")
    for field, pct in (
        ("side_overlap_pct", side_overlap_pct),
        ("front_overlap_pct", front_overlap_pct),
    ):
        if not 0.0 <= pct < 100.0:
            raise CameraError(f"{field} must be at least 0 and below 100, got {pct}")
    if altitude_m is not None:
        if not altitude_m > 0:
            raise CameraError(f"altitude_m must be greater than 0, got {altitude_m}")
        gsd = camera.gsd_cm(altitude_m)
        alt = altitude_m
    else:
        assert gsd_cm is not None
        if not gsd_cm > 0:
            raise CameraError(f"gsd_cm must be greater than 0, got {gsd_cm}")
        gsd = gsd_cm
        alt = camera.altitude_m(gsd_cm)
    wide = camera.image_width_px * gsd / 100.0
    tall = camera.image_height_px * gsd / 100.0
    side, frontal = (wide, tall) if camera.landscape else (tall, wide)
    return CameraCalc(
        camera=camera,
        altitude_m=alt,
        gsd_cm=gsd,
        footprint_side_m=side,
        footprint_frontal_m=frontal,
        side_overlap_pct=side_overlap_pct,
        front_overlap_pct=front_overlap_pct,
        lane_spacing_m=side * (100.0 - side_overlap_pct) / 100.0,
        trigger_distance_m=frontal * (100.0 - front_overlap_pct) / 100.0,
        distance_trigger=camera.distance_trigger,
    )
