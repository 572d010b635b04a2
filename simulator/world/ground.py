"""The simulated camera's ground: a synthetic texture known everywhere, with ArUco targets.

The ground is a horizontal plane at ``elevation_msl`` through a local east-north-up frame
(common.geodesy.LocalFrame) at ``origin``. Its colour at any (east, north) is the sum of
three layers of periodic coloured noise, each a 1024 x 1024 texture with its own texel size
(2 cm, 25 cm and 3 m: repeats every 20 m, 256 m and 3 km), so there are features at every
scale from a 12 MP photo's pixel up to a survey's whole area, and no two places within the
coarse period look alike. Everything follows from the seed.

The targets are ArUco markers (``cv2.aruco.DICT_4X4_50``), north up, each on a white
square one cell wider all round than the marker (the quiet zone a detector needs), with
their centres at known latitudes and longitudes: what the mosaic's accuracy is measured
against.

Sampling (``Ground.sample``) takes arrays of east/north metres and the ground distance one
output pixel spans, and reads each layer at the matching level of its mipmap, so a photo
from high up is not a moire of the 2 cm layer.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from common.geodesy import LocalFrame
from common.opencv import cv2

Image = npt.NDArray[np.uint8]
Floats = npt.NDArray[np.float64]

ARUCO_DICTIONARY = cv2.aruco.DICT_4X4_50
MARKER_CELLS = 6  # a 4 x 4 code inside a one-cell black border
TEXTURE_PX = 1024
# (texel size in metres, amplitude of the layer, spectral slope): fine grain, patches, fields.
LAYERS: tuple[tuple[float, float, float], ...] = (
    (0.02, 38.0, 1.2),
    (0.25, 45.0, 1.6),
    (3.0, 60.0, 2.2),
)
BASE_RGB = (96.0, 118.0, 72.0)  # a dry grass green; the layers move it to soil and crops


@dataclass(frozen=True, slots=True)
class GroundTarget:
    """An ArUco marker lying on the ground, north up: its id in DICT_4X4_50, the WGS84
    position of its centre, and the side of its black square in metres."""

    marker_id: int
    lat: float
    lon: float
    size_m: float


def _periodic_noise(rng: np.random.Generator, slope: float) -> npt.NDArray[np.float32]:
    """A TEXTURE_PX square of three-channel noise with a 1/f**slope spectrum, which tiles
    seamlessly (it is made in the frequency domain), scaled to unit standard deviation."""
    n = TEXTURE_PX
    fy = np.fft.fftfreq(n)[:, None]
    fx = np.fft.rfftfreq(n)[None, :]
    radius = np.hypot(fx, fy)
    radius[0, 0] = 1.0
    gain = radius**-slope
    gain[0, 0] = 0.0
    channels = []
    for _ in range(3):
        white = rng.standard_normal((n, n))
        layer = np.fft.irfft2(np.fft.rfft2(white) * gain, s=(n, n))
        channels.append(layer / layer.std())
    # Channels partly shared, so the colour varies more in brightness than in hue.
    shared = channels[0]
    mixed = [shared, 0.7 * shared + 0.3 * channels[1], 0.6 * shared + 0.4 * channels[2]]
    return np.stack(mixed, axis=-1).astype(np.float32)


def _mipmap(texture: npt.NDArray[np.float32]) -> list[npt.NDArray[np.float32]]:
    """Halvings down to 8 px; INTER_AREA on a power-of-two square averages 2 x 2 blocks,
    which keeps every level periodic."""
    levels = [texture]
    while levels[-1].shape[0] > 8:
        size = levels[-1].shape[0] // 2
        half: npt.NDArray[np.float32] = cv2.resize(  # type: ignore[assignment]
            levels[-1], (size, size), interpolation=cv2.INTER_AREA
        )
        levels.append(half)
    return levels


@dataclass
class Ground:
    """The textured ground plane and its targets around an origin (normally home)."""

    origin_lat: float
    origin_lon: float
    elevation_msl: float
    seed: int = 1
    targets: Sequence[GroundTarget] = ()
    frame: LocalFrame = field(init=False)
    _layers: list[tuple[float, list[npt.NDArray[np.float32]]]] = field(init=False, repr=False)
    _targets_en: list[tuple[GroundTarget, float, float, Image]] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.frame = LocalFrame(self.origin_lat, self.origin_lon, self.elevation_msl)
        rng = np.random.default_rng(self.seed)
        self._layers = [
            (texel, _mipmap(_periodic_noise(rng, slope) * amplitude))
            for texel, amplitude, slope in LAYERS
        ]
        dictionary = cv2.aruco.getPredefinedDictionary(ARUCO_DICTIONARY)
        self._targets_en = []
        for target in self.targets:
            east, north = self.frame.to_local(target.lat, target.lon)
            # One pixel per cell, plus the white quiet zone: sampled by cell, so edges stay
            # sharp at any scale.
            code = cv2.aruco.generateImageMarker(dictionary, target.marker_id, MARKER_CELLS)
            padded = np.full((MARKER_CELLS + 2, MARKER_CELLS + 2), 255, np.uint8)
            padded[1:-1, 1:-1] = code
            self._targets_en.append((target, east, north, padded))

    @classmethod
    def around(
        cls,
        lat: float,
        lon: float,
        elevation_msl: float,
        *,
        seed: int = 1,
        extent_m: float = 120.0,
        spacing_m: float = 30.0,
        size_m: float = 1.5,
    ) -> Ground:
        """A ground with a square grid of targets ``spacing_m`` apart out to ``extent_m``
        from (lat, lon) in each direction, ids counting from the south-west corner."""
        frame = LocalFrame(lat, lon, elevation_msl)
        steps = int(extent_m // spacing_m)
        targets: list[GroundTarget] = []
        offsets = [i * spacing_m for i in range(-steps, steps + 1)]
        for north in offsets:
            for east in offsets:
                marker_id = len(targets)
                if marker_id >= 50:  # DICT_4X4_50 has 50 codes
                    break
                t_lat, t_lon = frame.to_geo(east, north)
                targets.append(GroundTarget(marker_id, t_lat, t_lon, size_m))
        return cls(lat, lon, elevation_msl, seed, tuple(targets))

    def sample(self, east: Floats, north: Floats, pixel_m: float) -> Image:
        """The ground's colour (RGB, uint8) at each (east, north) metres, for an image whose
        pixels each span about ``pixel_m`` of ground."""
        shape = east.shape
        colour = np.empty((*shape, 3), np.float32)
        colour[...] = BASE_RGB
        for texel, levels in self._layers:
            # The finest level whose texels are no smaller than the output's pixels.
            level = min(len(levels) - 1, math.floor(math.log2(max(pixel_m / texel, 1.0))))
            texture = levels[level]
            size = texture.shape[0]
            scale = size / (TEXTURE_PX * texel)  # texture pixels per metre at this level
            # Wrap in float64 first: a float32 map of kilometres in centimetre texels would
            # lose the fraction.
            map_x = np.mod(east * scale, size).astype(np.float32)
            map_y = np.mod(-north * scale, size).astype(np.float32)
            colour += cv2.remap(
                texture, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP
            ).reshape(*shape, 3)
        rgb = np.clip(colour, 0, 255).astype(np.uint8)
        self._draw_targets(rgb, east, north)
        return rgb

    def _draw_targets(self, rgb: Image, east: Floats, north: Floats) -> None:
        if not self._targets_en:
            return
        e_min, e_max = float(east.min()), float(east.max())
        n_min, n_max = float(north.min()), float(north.max())
        for target, t_east, t_north, cells in self._targets_en:
            half = target.size_m * (MARKER_CELLS + 2) / MARKER_CELLS / 2.0
            if t_east + half < e_min or t_east - half > e_max:
                continue
            if t_north + half < n_min or t_north - half > n_max:
                continue
            cell_m = target.size_m / MARKER_CELLS
            # Column from the west edge of the quiet zone, row from its north edge.
            col = np.floor((east - (t_east - half)) / cell_m).astype(np.int64)
            row = np.floor(((t_north + half) - north) / cell_m).astype(np.int64)
            inside = (col >= 0) & (col < MARKER_CELLS + 2) & (row >= 0) & (row < MARKER_CELLS + 2)
            if inside.any():
                rgb[inside] = cells[row[inside], col[inside], None]
