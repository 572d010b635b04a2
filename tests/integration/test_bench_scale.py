"""bench/bench_scale.py runs, small: a hub, 5 agents at 10 Hz for 2 s, 2 dashboards, and
nothing lost or duplicated on the way (the figures themselves are the benchmark's)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parents[2] / "bench" / "bench_scale.py"


def test_the_scale_benchmark_loses_and_duplicates_nothing(tmp_path: Path) -> None:
    out = tmp_path / "figures.json"
    arguments = ["--vehicles", "5", "--rate", "10", "--dashboards", "2", "--duration", "2"]
    subprocess.run(
        [sys.executable, str(BENCH), *arguments, "--json", str(out)], check=True, timeout=150
    )
    figures = json.loads(out.read_text())
    assert figures["frames_sent"] >= 5 * 10  # at least a second's worth from each
    assert figures["rows_stored"] == figures["frames_sent"]
    assert (figures["db_lost"], figures["db_duplicates"], figures["unacked_vehicles"]) == (0, 0, 0)
    assert figures["dash_regressions"] == figures["dash_duplicates"] == 0
    assert figures["dash_final_missing"] == 0  # each dashboard ends at each last frame
    assert figures["dash_updates"] > 0
    assert figures["refused"] == []
    assert figures["dash_closed"] == []
