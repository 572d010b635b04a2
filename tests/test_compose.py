"""docker-compose.yml is valid (no Docker engine runs here, so the stack is not started)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
COMPOSE = shutil.which("docker-compose")
COMPOSE_SECRETS = {
    "GCS_ADMIN_PASSWORD": "compose-admin-password",
    "POSTGRES_PASSWORD": "compose-db-password",
    "SIM_1_TOKEN": "t1" * 16,
    "SIM_2_TOKEN": "t2" * 16,
}


def _config(env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    assert COMPOSE, "docker-compose is missing: scripts/setup.sh --dev installs it"
    return subprocess.run(
        [COMPOSE, "-f", str(ROOT / "docker-compose.yml"), "config"],
        capture_output=True,
        text=True,
        env={**os.environ, **env},
        timeout=60,
        check=False,
    )


def test_compose_file_is_valid_and_has_the_stack() -> None:
    result = _config(COMPOSE_SECRETS)
    assert result.returncode == 0, result.stderr
    for service in ("db:", "hub:", "sim-1:", "agent-1:", "sim-2:", "agent-2:"):
        assert f"  {service}" in result.stdout
    assert "postgresql+psycopg://" in result.stdout


@pytest.mark.skipif(COMPOSE is None, reason="checked by the test above")
@pytest.mark.parametrize(
    "missing", sorted(["GCS_ADMIN_PASSWORD", "POSTGRES_PASSWORD", "SIM_1_TOKEN"])
)
def test_compose_refuses_to_run_without_its_secrets(missing: str) -> None:
    env = {**os.environ, **COMPOSE_SECRETS}
    del env[missing]
    result = subprocess.run(
        [str(COMPOSE), "-f", str(ROOT / "docker-compose.yml"), "config", "-q"],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
        check=False,
    )
    assert result.returncode != 0
    assert missing in result.stderr
