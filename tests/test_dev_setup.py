"""The development setup itself: `make test` installs quietly, and tests that need
PostgreSQL say why they are skipped where it is missing (but never in CI)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from gcs.launcher import free_port

ROOT = Path(__file__).resolve().parent.parent
POSTGRES_TEST = "tests/integration/test_storage.py::test_migrations_match_the_models[postgresql]"


def _run_postgres_test_without_server(ci: str | None) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "GCS_TEST_POSTGRES_ADDRESS": f"127.0.0.1:{free_port()}"}
    env.pop("CI", None)
    if ci is not None:
        env["CI"] = ci
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider", POSTGRES_TEST],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        check=False,
    )


def test_postgres_tests_are_skipped_with_a_reason_when_the_server_is_away() -> None:
    result = _run_postgres_test_without_server(ci=None)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "1 skipped" in result.stdout
    assert "PostgreSQL is not reachable at 127.0.0.1:" in result.stdout


def test_postgres_tests_fail_loudly_in_ci_when_the_server_is_away() -> None:
    result = _run_postgres_test_without_server(ci="true")
    assert result.returncode == 1, result.stdout + result.stderr
    assert "1 error" in result.stdout or "1 failed" in result.stdout
    assert "skipped" not in result.stdout


def test_editable_install_prints_no_setuptools_warnings(tmp_path: Path) -> None:
    """`make test` reinstalls the project (pip install -e) on every run; setuptools must
    have nothing to warn about. Installed into a scratch prefix, so the venv is untouched."""
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "-q",
            "--no-deps",
            "--ignore-installed",
            "--prefix",
            str(tmp_path / "prefix"),
            "-e",
            str(ROOT),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    # Python warning classes (SetuptoolsDeprecationWarning, BuildBackendWarning...), not
    # pip's own "WARNING:" notes about where it looks for packages.
    output = result.stdout + result.stderr
    assert "Warning" not in output, output
    assert "!!" not in output, output
