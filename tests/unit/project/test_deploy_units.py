"""The systemd units in deploy/ give the hub a state directory that is its data directory,
and the deployer's guide walks through the hub's user and folders."""

from __future__ import annotations

from pathlib import Path

from tests.support.docs import page_holding
from vehicle_agents.cli import EXIT_VEHICLE_ID_IN_USE

ROOT = Path(__file__).parents[3]


def _settings(unit: Path) -> dict[str, list[str]]:
    """Every ``key=value`` of a unit (keys may repeat, as Environment= does)."""
    found: dict[str, list[str]] = {}
    for line in unit.read_text().splitlines():
        if "=" in line and not line.startswith(("#", "[")):
            key, _, value = line.partition("=")
            found.setdefault(key.strip(), []).append(value.strip())
    return found


def test_the_hub_unit_has_its_data_directory_as_state_directory() -> None:
    unit = _settings(ROOT / "deploy" / "gcs-hub.service")
    environment = dict(value.split("=", 1) for value in unit["Environment"])
    (state,) = unit["StateDirectory"]
    assert environment["GCS_DATA_DIR"] == f"/var/lib/{state}"
    assert unit["User"] == [state]
    assert unit["ProtectSystem"] == ["strict"]
    assert "GCS_FRONTEND_DIR" in environment


def test_the_readme_gives_the_hub_service_steps() -> None:
    lead = "**Running the hub as a service.**"
    readme = page_holding(lead).read_text()
    steps = readme[readme.index(lead) :]
    for step in (
        "useradd --system",
        "install -d -m 750 -o root -g gcs /etc/gcs",
        "deploy/gcs-hub.service /etc/systemd/system/",
        "systemctl enable --now gcs-hub",
    ):
        assert step in steps, step


def test_the_agent_unit_does_not_restart_an_agent_refused_its_vehicle_id() -> None:
    """An id clash (close 4409) ends the agent with EXIT_VEHICLE_ID_IN_USE: restarting it
    would only knock again, so the unit must leave it stopped for a person to fix."""
    unit = _settings(ROOT / "deploy" / "gcs-agent.service")
    assert unit["Restart"] == ["always"]
    (prevented,) = unit["RestartPreventExitStatus"]
    assert str(EXIT_VEHICLE_ID_IN_USE) in prevented.split()


def test_the_agent_units_state_is_private() -> None:
    """systemd makes a StateDirectory 0755 unless told: the outbox and .tlogs in it are
    the vehicle's flight data."""
    unit = _settings(ROOT / "deploy" / "gcs-agent.service")
    assert unit["StateDirectoryMode"] == ["0700"]
    assert unit["UMask"] == ["0077"]


def test_the_proxies_let_an_agent_s_tlog_through() -> None:
    """The hub takes a .tlog of up to max_tlog_bytes in one body on its upload route;
    each proxy in deploy/ takes it there (and keeps 2 MB elsewhere)."""
    import re

    from backend.settings import HubSettings

    route = "/api/v1/vehicles/survey_1/tlogs"
    limit = HubSettings.model_fields["max_tlog_bytes"].default
    for name in ("nginx.conf", "nginx-scaled.conf"):
        text = (ROOT / "deploy" / name).read_text()
        (pattern, block) = re.findall(r"location ~ (\S+) \{([^}]*)\}", text)[0]
        assert re.match(pattern, route), name
        (size,) = re.findall(r"client_max_body_size (\d+)m;", block)
        assert int(size) * 2**20 >= limit, name
        assert "proxy_request_buffering off;" in block
        assert "client_max_body_size 2m;" in text  # everything else
    caddy = (ROOT / "deploy" / "Caddyfile").read_text()
    (pattern,) = set(re.findall(r"path_regexp (\S+)", caddy))
    assert re.match(pattern, route)
    (size,) = re.findall(r"request_body @tlog_upload \{\s*max_size (\d+)MiB", caddy)
    assert int(size) * 2**20 >= limit
