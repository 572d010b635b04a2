"""`gcs tiles`: the hub's offline base maps (``.mbtiles`` and ``.pmtiles`` files).

The hub serves every such file in its tiles folder (``GCS_TILES_DIR``, else
``<GCS_DATA_DIR>/tiles``) by name and notices new ones without a restart; these commands
check a file before it goes there, list what is there, and take one away.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
from pathlib import Path


def add_tiles_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data-dir", type=Path, help="the hub's data directory (GCS_DATA_DIR)")
    parser.add_argument("--tiles-dir", type=Path, help="the tiles folder (GCS_TILES_DIR)")
    actions = parser.add_subparsers(dest="action", required=True)
    imported = actions.add_parser("import", help="check a tile set and copy it in")
    imported.add_argument("file", type=Path, help="a .mbtiles or .pmtiles file")
    imported.add_argument("--name", help="the name it appears under (default: the file's)")
    imported.add_argument("--replace", action="store_true", help="replace a set of that name")
    actions.add_parser("list", help="the tile sets the hub serves")
    removed = actions.add_parser("remove", help="take a tile set away")
    removed.add_argument("name")


def tiles_folder(args: argparse.Namespace) -> Path:
    """The same folder the hub uses: the flags, then the hub's variables, then data/tiles."""
    if args.tiles_dir:
        return Path(args.tiles_dir)
    if args.data_dir:
        return Path(args.data_dir) / "tiles"
    if os.environ.get("GCS_TILES_DIR"):
        return Path(os.environ["GCS_TILES_DIR"])
    return Path(os.environ.get("GCS_DATA_DIR", "data")) / "tiles"


def run(args: argparse.Namespace) -> int:
    from backend.mapping.tiles import TileSetError

    folder = tiles_folder(args)
    try:
        if args.action == "import":
            return _import(folder, args.file, args.name, args.replace)
        if args.action == "list":
            return _list(folder)
        return _remove(folder, args.name)
    except (TileSetError, OSError) as error:
        print(f"gcs tiles: {error}", file=sys.stderr)
        return 2


def _describe(info: object) -> str:
    from backend.mapping.tiles import TileSetInfo

    assert isinstance(info, TileSetInfo)
    bounds = ", ".join(f"{value:g}" for value in info.bounds) if info.bounds else "unknown"
    return (
        f"{info.name}\t{info.kind}\t{info.media_type}\tzoom {info.min_zoom}-{info.max_zoom}"
        f"\tbounds {bounds}"
    )


def _import(folder: Path, source: Path, name: str | None, replace: bool) -> int:
    from backend.mapping.tiles import SUFFIXES, TileSetError, check_name, open_tile_set

    if source.suffix not in SUFFIXES:
        raise TileSetError(f"{source.name}: a tile set is a .mbtiles or a .pmtiles file")
    target = folder / (check_name(name or source.stem) + source.suffix)
    clashing = [folder / (target.stem + suffix) for suffix in SUFFIXES]
    existing = [path for path in clashing if path.exists()]
    if existing and not replace:
        raise TileSetError(f"a tile set named {target.stem!r} is installed: add --replace")
    opened = open_tile_set(source)  # refuses a file the hub could not serve, with the reason
    opened.close()
    folder.mkdir(parents=True, exist_ok=True)
    # Copied under a name the hub ignores, then renamed: it never opens half a file.
    partial = folder / f".{target.name}.part"
    shutil.copyfile(source, partial)
    for path in existing:
        path.unlink()
    partial.replace(target)
    installed = open_tile_set(target)
    print(f"installed {_describe(installed.info)}\n  {target}")
    installed.close()
    return 0


def _list(folder: Path) -> int:
    from backend.mapping.tiles import TileLibrary

    library = TileLibrary(folder)
    sets = library.sets()
    library.close()
    if not sets:
        print(f"no tile sets in {folder}")
    for info in sets:
        print(_describe(info))
    return 0


def _remove(folder: Path, name: str) -> int:
    from backend.mapping.tiles import SUFFIXES, TileSetError, check_name

    paths = [folder / (check_name(name) + suffix) for suffix in SUFFIXES]
    found = [path for path in paths if path.exists()]
    if not found:
        raise TileSetError(f"no tile set named {name!r} in {folder}")
    for path in found:
        path.unlink()
        print(f"removed {path}")
    return 0
