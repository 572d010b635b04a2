"""The dashboard's TypeScript unit tests (vitest: the store, stick shaping, label placement).

They run here, inside pytest, so that `make test`, CI and a plain `pytest` all run them
and a failing one fails the suite with vitest's own report."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

FRONTEND = Path(__file__).resolve().parents[3] / "frontend"
VITEST = FRONTEND / "node_modules" / "vitest" / "vitest.mjs"


def test_dashboard_unit_tests_pass() -> None:
    node = shutil.which("node")
    assert node, "node is required to build and test the dashboard"
    # Not a skip: a skipped run would let a failing TypeScript test pass the suite unseen.
    assert VITEST.is_file(), "vitest is missing: run scripts/setup.sh (npm ci in frontend/)"
    run = subprocess.run(
        [node, str(VITEST), "run", "--reporter=dot"],
        capture_output=True,
        text=True,
        cwd=FRONTEND,
        env={**os.environ, "NO_COLOR": "1", "CI": "1"},
        timeout=300,
        check=False,
    )
    assert run.returncode == 0, f"vitest failed:\n{run.stdout}\n{run.stderr}"
