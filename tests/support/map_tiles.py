"""Tile sets made by tests: solid-colour PNG tiles in an MBTiles or a PMTiles file."""

from __future__ import annotations

import io
import math
import random
import sqlite3
import struct
import zlib
from pathlib import Path

from pmtiles.tile import Compression, TileType, zxy_to_tileid
from pmtiles.writer import Writer

Tiles = dict[tuple[int, int, int], bytes]  # (z, x, y) in XYZ order -> tile bytes


def png_tile(rgb: tuple[int, int, int], size: int = 256) -> bytes:
    """A solid ``size`` x ``size`` PNG (8-bit RGB), written by hand: no imaging library."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    row = b"\x00" + bytes(rgb) * size  # filter type 0, then the pixels
    header = struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(row * size, 9))
        + chunk(b"IEND", b"")
    )


def write_mbtiles(path: Path, tiles: Tiles, **metadata: str) -> Path:
    """The MBTiles 1.3 schema; rows in TMS order (y from the south), as the spec says."""
    zooms = [z for z, _, _ in tiles]
    values = {"name": path.stem, "format": "png", "minzoom": str(min(zooms))}
    values |= {"maxzoom": str(max(zooms)), **metadata}
    with sqlite3.connect(path) as db:
        db.execute("CREATE TABLE metadata (name TEXT, value TEXT)")
        db.execute(
            "CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER,"
            " tile_data BLOB)"
        )
        db.execute("CREATE UNIQUE INDEX tile_index ON tiles (zoom_level, tile_column, tile_row)")
        db.executemany("INSERT INTO metadata VALUES (?, ?)", values.items())
        db.executemany(
            "INSERT INTO tiles VALUES (?, ?, ?, ?)",
            [(z, x, (1 << z) - 1 - y, data) for (z, x, y), data in tiles.items()],
        )
    return path


def write_pmtiles(path: Path, tiles: Tiles, attribution: str = "") -> Path:
    with path.open("wb") as file:
        writer = Writer(file)
        for (z, x, y), data in sorted(tiles.items(), key=lambda item: zxy_to_tileid(*item[0])):
            writer.write_tile(zxy_to_tileid(z, x, y), data)
        writer.finalize(
            {
                "tile_type": TileType.PNG,
                "tile_compression": Compression.NONE,
                "min_lon_e7": -1800000000,
                "min_lat_e7": -850000000,
                "max_lon_e7": 1800000000,
                "max_lat_e7": 850000000,
                "center_zoom": 0,
                "center_lon_e7": 0,
                "center_lat_e7": 0,
            },
            {"attribution": attribution},
        )
    return path


def _tile_xy(lat: float, lon: float, zoom: int) -> tuple[float, float]:
    """Web Mercator, in tiles (fractional) at ``zoom``."""
    n = 2**zoom
    y = (1 - math.asinh(math.tan(math.radians(lat))) / math.pi) / 2 * n
    return (lon + 180) / 360 * n, y


def farmland_tiles(
    home: tuple[float, float], zooms: range, radius_m: float, seed: int = 16
) -> Tiles:
    """A made-up landscape around ``home`` as PNG tiles: fields of a few crops with
    hedges between them, a road with its centre line, a farm track, a pond, a few
    buildings and a concrete pad under the fleet. Drawn from shapes in metres, so each
    zoom shows the same place; it stands in for imagery where a test has no internet."""
    from PIL import Image, ImageDraw  # the hub's own dependency (mosaic), a test extra here

    rng = random.Random(seed)
    lat0, lon0 = home
    per_lat = 111_320.0
    per_lon = per_lat * math.cos(math.radians(lat0))

    def geo(east: float, north: float) -> tuple[float, float]:
        return lat0 + north / per_lat, lon0 + east / per_lon

    def rect(west: float, south: float, east: float, north: float) -> list[tuple[float, float]]:
        return [(west, south), (east, south), (east, north), (west, north)]

    Shape = tuple[str, list[tuple[float, float]], tuple[int, int, int], int]
    shapes: list[Shape] = []  # kind, points in metres (east, north), colour, width
    crops = [(201, 183, 112), (124, 160, 82), (150, 120, 86), (170, 190, 96), (96, 138, 70)]
    size = 110.0
    for i in range(-8, 9):
        for j in range(-8, 9):
            e, n = i * size, j * size
            if abs(e) > radius_m + size or abs(n) > radius_m + size:
                continue
            cut = rng.uniform(0.3, 0.7) * size
            for a, b in ((0.0, cut), (cut, size)):  # each block split in two fields
                field = rect(e + 3, n + a + 2, e + size - 3, n + b - 2)
                shapes.append(("polygon", field, rng.choice(crops), 0))
    shapes.append(("polygon", rect(-22, -22, 22, 22), (178, 176, 168), 0))  # the pad
    track = [(-40.0, -900.0), (-35.0, -200.0), (-30.0, 30.0), (60.0, 120.0), (400.0, 160.0)]
    shapes.append(("line", track, (170, 146, 108), 4))
    road = [(-900.0, -260.0), (-200.0, -140.0), (150.0, -100.0), (900.0, 40.0)]
    shapes.append(("line", road, (92, 92, 96), 9))
    shapes.append(("line", road, (230, 226, 200), 1))
    pond = [
        (180 + 45 * math.cos(t / 12 * math.tau), 210 + 30 * math.sin(t / 12 * math.tau))
        for t in range(12)
    ]
    shapes.append(("polygon", pond, (64, 104, 140), 0))
    for e, n in ((-150, -118), (-120, -112), (60, -86), (95, -80), (-170, -168)):
        shapes.append(
            ("polygon", [(e, n), (e + 18, n), (e + 18, n + 12), (e, n + 12)], (190, 180, 170), 0)
        )

    tiles: Tiles = {}
    for zoom in zooms:
        corner_a = _tile_xy(*geo(-radius_m, radius_m), zoom)
        corner_b = _tile_xy(*geo(radius_m, -radius_m), zoom)
        projected = [
            (kind, [_tile_xy(*geo(e, n), zoom) for e, n in points], colour, width)
            for kind, points, colour, width in shapes
        ]
        metres_per_px = 40_075_016 * math.cos(math.radians(lat0)) / (256 * 2**zoom)
        for x in range(int(corner_a[0]), int(corner_b[0]) + 1):
            for y in range(int(corner_a[1]), int(corner_b[1]) + 1):
                image = Image.new("RGB", (256, 256), (88, 120, 70))  # hedges and grass
                draw = ImageDraw.Draw(image)
                for kind, points, colour, width in projected:
                    pixels = [((px - x) * 256, (py - y) * 256) for px, py in points]
                    if kind == "polygon":
                        draw.polygon(pixels, fill=colour)
                    else:
                        draw.line(pixels, fill=colour, width=max(1, round(width / metres_per_px)))
                out = io.BytesIO()
                image.save(out, format="PNG")
                tiles[(zoom, x, y)] = out.getvalue()
    return tiles
