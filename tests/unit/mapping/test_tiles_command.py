"""`gcs tiles import | list | remove`: what goes into the hub's tiles folder."""

from __future__ import annotations

from pathlib import Path

import pytest

from backend.mapping.tiles import TileLibrary
from gcs.cli import main
from tests.support.map_tiles import png_tile, write_mbtiles, write_pmtiles

TILE = png_tile((10, 20, 30), 8)


def test_import_list_and_remove(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = tmp_path / "data"
    source = write_mbtiles(tmp_path / "download.mbtiles", {(0, 0, 0): TILE})
    assert main(["tiles", "--data-dir", str(data), "import", str(source), "--name", "field"]) == 0
    assert "installed field\tmbtiles\timage/png" in capsys.readouterr().out
    assert (data / "tiles" / "field.mbtiles").is_file()
    assert [p.name for p in (data / "tiles").iterdir()] == ["field.mbtiles"]  # no .part left
    library = TileLibrary(data / "tiles")
    assert library.tile("field", 0, 0, 0)[1] == TILE
    library.close()

    # A second set of the same name needs --replace, whatever its format.
    other = write_pmtiles(tmp_path / "field.pmtiles", {(0, 0, 0): TILE})
    assert main(["tiles", "--data-dir", str(data), "import", str(other)]) == 2
    assert "add --replace" in capsys.readouterr().err
    assert main(["tiles", "--data-dir", str(data), "import", str(other), "--replace"]) == 0
    assert sorted(p.name for p in (data / "tiles").iterdir()) == ["field.pmtiles"]

    capsys.readouterr()
    assert main(["tiles", "--tiles-dir", str(data / "tiles"), "list"]) == 0
    assert capsys.readouterr().out.startswith("field\tpmtiles\timage/png\tzoom 0-0")
    assert main(["tiles", "--data-dir", str(data), "remove", "field"]) == 0
    assert list((data / "tiles").iterdir()) == []


def test_a_file_the_hub_could_not_serve_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    vector = write_mbtiles(tmp_path / "roads.mbtiles", {(0, 0, 0): b"\x1a\x00"}, format="pbf")
    assert main(["tiles", "--data-dir", str(tmp_path), "import", str(vector)]) == 2
    assert "only raster tiles are drawn" in capsys.readouterr().err
    assert not (tmp_path / "tiles").exists()
