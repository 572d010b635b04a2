"""docker-compose.yml is valid (no Docker engine runs here, so the stack is not started)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest
import yaml
from pydantic import ValidationError

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


def _hub_settings_from_compose(env: dict[str, str], monkeypatch: pytest.MonkeyPatch) -> Any:
    """The hub's settings exactly as the compose file would start it: its environment
    and its command line, through the hub's own validation."""
    from backend.settings import HubSettings

    result = _config(env)
    assert result.returncode == 0, result.stderr
    hub = yaml.safe_load(result.stdout)["services"]["hub"]
    for name in list(os.environ):
        if name.startswith("GCS_") or name.endswith("_FILE") or name == "DATABASE_URL":
            monkeypatch.delenv(name)
    for name, value in hub["environment"].items():
        monkeypatch.setenv(name, str(value))
    command = hub["command"]
    return HubSettings(host=command[command.index("--host") + 1])


def test_compose_runs_the_hub_in_production_mode(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.chdir(tmp_path)
    settings = _hub_settings_from_compose(COMPOSE_SECRETS, monkeypatch)
    assert settings.environment == "production"
    assert settings.host == "0.0.0.0"
    ports = yaml.safe_load(_config(COMPOSE_SECRETS).stdout)["services"]["hub"]["ports"]
    # Published on loopback only (compose v1 renders "ip:published:target", v2 a mapping).
    host_ips = [p.split(":")[0] if isinstance(p, str) else p.get("host_ip") for p in ports]
    assert host_ips == ["127.0.0.1"]


@pytest.mark.parametrize(
    "weak",
    [{"GCS_ADMIN_PASSWORD": "admin"}, {"SIM_1_TOKEN": "short-token"}],
    ids=["admin-password", "short-agent-token"],
)
def test_compose_hub_refuses_weak_secrets(
    weak: dict[str, str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValidationError, match="refusing default secrets in production"):
        _hub_settings_from_compose({**COMPOSE_SECRETS, **weak}, monkeypatch)
