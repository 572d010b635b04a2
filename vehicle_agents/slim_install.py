"""Remove the MAVLink dialects the agent never loads from an installed pymavlink.

pymavlink's wheel carries every dialect generated twice (MAVLink 1 and 2), and pip
compiles each to bytecode: 88 of the 92 MB it takes once installed. The agent loads one,
ardupilotmega (which holds common and minimal) over MAVLink 2 (`fcu/dialect.py`).
pip cannot leave parts of a package out, so this deletes them after the install:

    sudo /opt/gcs/.venv/bin/python -m vehicle_agents.slim_install

Run it again after every install or upgrade of pymavlink (which brings them back). pip's
record of the package still lists the deleted files; `pip uninstall` and upgrades do not
mind. Kept: ardupilotmega, common and minimal for MAVLink 1 and 2 (their modules, bytecode
and XML), the generator (mavutil imports its parser), and everything outside
``dialects/``. An operator who sets MAVLINK_DIALECT to another dialect keeps it with
``--keep NAME``.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path

from vehicle_agents.fcu.dialect import DIALECT

KEPT_DIALECTS = frozenset({DIALECT, "common", "minimal"})
WIRE_VERSIONS = ("v10", "v20")


def unneeded_files(pymavlink_dir: Path, keep: Iterable[str] = KEPT_DIALECTS) -> Iterator[Path]:
    """The generated dialect files (module, bytecode, XML) of every dialect not kept."""
    kept = set(keep)
    for version in WIRE_VERSIONS:
        folder = pymavlink_dir / "dialects" / version
        candidates = [*folder.glob("*.py"), *folder.glob("*.xml")]
        candidates += folder.glob("__pycache__/*.pyc")
        for path in candidates:
            dialect = path.name.split(".")[0]  # "common.cpython-311.pyc" -> "common"
            if dialect != "__init__" and dialect not in kept:
                yield path


def slim(pymavlink_dir: Path, keep: Iterable[str] = KEPT_DIALECTS) -> int:
    """Delete what the agent never loads; the number of bytes freed."""
    freed = 0
    for path in sorted(unneeded_files(pymavlink_dir, keep)):
        freed += path.stat().st_size
        path.unlink()
    return freed


def installed_pymavlink() -> Path:
    import pymavlink

    return Path(pymavlink.__file__).parent


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m vehicle_agents.slim_install", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--keep", action="append", default=[], metavar="DIALECT")
    parser.add_argument("--dry-run", action="store_true", help="list, do not delete")
    args = parser.parse_args(argv)
    keep = KEPT_DIALECTS | set(args.keep)
    wanted = os.environ.get("MAVLINK_DIALECT")
    if wanted is not None and wanted not in keep:
        print(
            f"MAVLINK_DIALECT={wanted} is set here; add --keep {wanted} to keep it",
            file=sys.stderr,
        )
        return 2
    folder = installed_pymavlink()
    if args.dry_run:
        for path in unneeded_files(folder, keep):
            print(path)
        return 0
    freed = slim(folder, keep)
    mib = freed / 2**20  # as du -m counts
    print(f"{folder}: removed {mib:.1f} MB of dialects the agent does not load")
    return 0


if __name__ == "__main__":
    sys.exit(main())
