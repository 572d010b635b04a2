"""The dashboard's MAV_CMD and MAV_FRAME values are pymavlink's, written into
frontend/src/generated/mavlink.ts by scripts/gen_mavlink_ts.py, and its sources use those
names rather than numbers typed by hand."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

ROOT = Path(__file__).resolve().parents[3]
SCRIPT = ROOT / "scripts" / "gen_mavlink_ts.py"
GENERATED = ROOT / "frontend" / "src" / "generated" / "mavlink.ts"
MISSIONS = ROOT / "frontend" / "src" / "missions"


def test_the_generated_names_match_pymavlink() -> None:
    check = subprocess.run(
        [sys.executable, str(SCRIPT), "--check"], capture_output=True, text=True, timeout=60
    )
    assert check.returncode == 0, check.stdout + check.stderr
    constants = dict(re.findall(r"^export const (\w+) = (\d+);$", GENERATED.read_text(), re.M))
    assert constants["MAV_CMD_NAV_WAYPOINT"] == str(mavlink2.MAV_CMD_NAV_WAYPOINT)
    assert constants["MAV_FRAME_GLOBAL_RELATIVE_ALT"] == str(mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT)


# A MAV_CMD or MAV_FRAME number in the mission code: a table keyed by one, a list of them,
# a field compared with or set to one.
_HAND_TYPED = re.compile(
    r"^\s*\d+\s*:\s*\"|"  # { 16: "Waypoint" }
    r"\b(?:command|frame)\s*(?:===?|!==?|:)\s*\d+\b|"  # item.command === 22, frame: 2
    r"\[\s*\d{2,}\s*(?:,\s*\d+\s*){2,}\]|"  # [16, 17, 18] (not a [0, 0, 0] position)
    r"\b[A-Z_]+\s*:\s*\d+\s*,"  # { WAYPOINT: 16, ... }
)


def test_the_mission_code_types_no_mavlink_number() -> None:
    found = [
        f"{path.name}:{number}: {line.strip()}"
        for path in sorted(MISSIONS.glob("*.ts"))
        for number, line in enumerate(path.read_text().splitlines(), start=1)
        if _HAND_TYPED.search(line)
    ]
    assert found == [], "use the names of frontend/src/generated/mavlink.ts"


def test_the_check_sees_numbers_typed_by_hand() -> None:
    for line in (
        '  16: "Waypoint",',
        "if (item.command === 22)",
        "frame: 2,",
        "new Set<number>([16, 17, 18, 19])",
        "  WAYPOINT: 16,",
    ):
        assert _HAND_TYPED.search(line), line
    for line in ("frame: mav.MAV_FRAME_MISSION,", "param1: 30,", "[CMD.TAKEOFF, CMD.LAND]"):
        assert not _HAND_TYPED.search(line), line
