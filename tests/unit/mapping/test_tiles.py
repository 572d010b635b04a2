"""Offline tile sets read from their files (backend/mapping/tiles.py)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from backend.mapping.tiles import TileLibrary, TileSetError, UnknownTileSet, open_tile_set
from tests.support.map_tiles import png_tile, write_mbtiles, write_pmtiles

RED, GREEN, BLUE = png_tile((255, 0, 0), 8), png_tile((0, 255, 0), 8), png_tile((0, 0, 255), 8)
# At zoom 1, XYZ y=0 is the northern row; MBTiles stores it as TMS row 1.
TILES = {(0, 0, 0): RED, (1, 1, 0): GREEN, (1, 1, 1): BLUE}


def test_mbtiles_rows_are_flipped_to_xyz(tmp_path: Path) -> None:
    path = write_mbtiles(tmp_path / "field.mbtiles", TILES, attribution="survey 2026")
    source = open_tile_set(path)
    try:
        assert source.tile(1, 1, 0) == GREEN  # the north-east tile, not the south-east
        assert source.tile(1, 1, 1) == BLUE
        assert source.tile(0, 0, 0) == RED
        assert source.tile(1, 0, 0) is None
        info = source.info
        assert (info.name, info.kind, info.media_type) == ("field", "mbtiles", "image/png")
        assert (info.min_zoom, info.max_zoom, info.attribution) == (0, 1, "survey 2026")
        # No bounds in the metadata: those of the tiles at the deepest zoom (the east half).
        assert info.bounds is not None
        assert info.bounds[0] == 0.0
        assert info.bounds[2] == 180.0
        assert info.bounds[1] == pytest.approx(-85.0511, abs=1e-3)
    finally:
        source.close()


def test_pmtiles_are_read_in_xyz_order(tmp_path: Path) -> None:
    source = open_tile_set(write_pmtiles(tmp_path / "area.pmtiles", TILES, "osm"))
    try:
        assert source.tile(1, 1, 0) == GREEN
        assert source.tile(1, 1, 1) == BLUE
        assert source.tile(1, 0, 1) is None
        assert (source.info.kind, source.info.max_zoom, source.info.attribution) == (
            "pmtiles",
            1,
            "osm",
        )
        assert source.info.bounds == (-180.0, -85.0, 180.0, 85.0)
    finally:
        source.close()


def test_vector_tiles_and_foreign_files_are_refused_with_a_reason(tmp_path: Path) -> None:
    vector = write_mbtiles(tmp_path / "roads.mbtiles", TILES, format="pbf")
    with pytest.raises(TileSetError, match="only raster tiles"):
        open_tile_set(vector)
    junk = tmp_path / "junk.pmtiles"
    junk.write_bytes(b"not a tile set at all" * 10)
    with pytest.raises(TileSetError, match="not a PMTiles"):
        open_tile_set(junk)
    with pytest.raises(TileSetError, match="not a tile set name"):
        open_tile_set(write_mbtiles(tmp_path / "-bad name.mbtiles", TILES))


def test_the_library_notices_files_added_replaced_and_removed(tmp_path: Path) -> None:
    library = TileLibrary(tmp_path)
    try:
        assert library.sets() == []
        path = write_mbtiles(tmp_path / "field.mbtiles", {(0, 0, 0): RED})
        (tmp_path / "broken.mbtiles").write_bytes(b"garbage")  # skipped, logged once
        (tmp_path / "notes.txt").write_text("not a tile set")
        [first] = library.sets()
        assert library.tile("field", 0, 0, 0) == (first, RED)

        path.unlink()
        write_mbtiles(path, {(0, 0, 0): BLUE})
        os.utime(path, ns=(1, 1))  # a different modification time, as a copy would have
        [second] = library.sets()
        assert second.version != first.version
        assert library.tile("field", 0, 0, 0) == (second, BLUE)

        path.unlink()
        assert library.sets() == []
        with pytest.raises(UnknownTileSet):
            library.tile("field", 0, 0, 0)
    finally:
        library.close()
