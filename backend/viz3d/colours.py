"""One colour per vehicle, from its id: the same on the 2D map and in the 3D view
(frontend/src/viz3d/colours.ts computes it the same way for the 2D map's labels;
tests/browser/test_viz3d.py checks that the two agree)."""

from __future__ import annotations

import zlib

# Distinct on the dark map and the light 3D background alike.
PALETTE: tuple[str, ...] = (
    "#e6194b",
    "#3cb44b",
    "#4363d8",
    "#f58231",
    "#911eb4",
    "#42d4f4",
    "#f032e6",
    "#bfef45",
    "#469990",
    "#9a6324",
    "#800000",
    "#808000",
)


def vehicle_colour(vehicle_id: str) -> str:
    """``#rrggbb``: the palette entry picked by the CRC-32 of the id's UTF-8 bytes."""
    return PALETTE[zlib.crc32(vehicle_id.encode()) % len(PALETTE)]


def rgb(colour: str) -> tuple[int, int, int]:
    return int(colour[1:3], 16), int(colour[3:5], 16), int(colour[5:7], 16)
