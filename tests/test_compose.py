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


# -- the scaled profile: two hubs behind a proxy, on PostgreSQL and NATS ---------------

SCALED_SECRETS = {
    "SCALED_ADMIN_PASSWORD": "scaled-admin-password",
    "SCALED_DB_PASSWORD": "scaled-db-password",
    "FLEET_1_TOKEN": "f1" * 16,
    "FLEET_2_TOKEN": "f2" * 16,
    "SCALED_BUS_PASSWORD": "12e3" + "b1" * 16,  # unquoted, NATS could not parse it
}
SCALED_HUBS = ("hub-a", "hub-b")


def _scaled_services() -> dict[str, Any]:
    result = _config({**COMPOSE_SECRETS, **SCALED_SECRETS})
    assert result.returncode == 0, result.stderr
    services: dict[str, Any] = yaml.safe_load(result.stdout)["services"]
    return services


def _nginx_directives(text: str) -> list[list[str]]:
    """Each directive of an nginx file as its words, comments left out."""
    lines = (line.split("#", 1)[0] for line in text.splitlines())
    return [
        part.split()
        for part in " ".join(lines).replace("{", ";").replace("}", ";").split(";")
        if part.split()
    ]


def test_the_scaled_profile_has_two_hubs_behind_a_proxy_on_postgres_and_nats() -> None:
    services = _scaled_services()
    scaled = {name for name, service in services.items() if "scaled" in service.get("profiles", [])}
    assert scaled == {
        "scaled-db",
        "nats",
        *SCALED_HUBS,
        "proxy",
        "fleet-sim-1",
        "fleet-agent-1",
        "fleet-sim-2",
        "fleet-agent-2",
    }
    # The default stack stays as it was: `docker compose up` starts no scaled service.
    assert {"db", "hub", "sim-1", "agent-1"} <= set(services) - scaled
    hubs = [services[name]["environment"] for name in SCALED_HUBS]
    assert hubs[0] == hubs[1], "the two hubs must be one deployment"
    assert hubs[0]["GCS_BUS_URL"] == "nats://nats:4222"
    assert "@scaled-db:5432/" in hubs[0]["DATABASE_URL"]
    # The single hub stays alone, with its in-process bus.
    assert "GCS_BUS_URL" not in services["hub"]["environment"]


def test_the_scaled_hubs_start_in_production_mode(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from backend.settings import HubSettings

    monkeypatch.chdir(tmp_path)
    services = _scaled_services()
    for name in SCALED_HUBS:
        for variable in list(os.environ):
            if variable.startswith("GCS_") or variable == "DATABASE_URL":
                monkeypatch.delenv(variable)
        for variable, value in services[name]["environment"].items():
            monkeypatch.setenv(variable, str(value))
        settings = HubSettings()
        assert settings.environment == "production"
        assert settings.bus_url == "nats://nats:4222"
        assert settings.bus_has_credentials
        assert settings.bus_user == "gcs-hub"
        assert set(settings.enrolment_tokens()) == {"fleet_1", "fleet_2"}


def test_the_scaled_nats_server_admits_only_the_hubs_login() -> None:
    """The nats service runs deploy/nats-server.conf with the password the hubs present:
    that very file, run here, refuses a client without the login and admits the hubs."""
    from tests.support.nats_server import login_refused, nats_server

    services = _scaled_services()
    bus = services["nats"]
    [mount] = [volume for volume in bus["volumes"] if "nats-server.conf" in str(volume)]
    source, target = (
        (mount["source"], mount["target"]) if isinstance(mount, dict) else str(mount).split(":")[:2]
    )
    command = bus["command"]
    assert command[command.index("--config") + 1] == target
    assert "ports" not in bus  # only the hubs, on the compose network, reach it
    password = SCALED_SECRETS["SCALED_BUS_PASSWORD"]
    # Quoted for the server's config parser, which would read 1234 as a number.
    assert bus["environment"]["GCS_BUS_PASSWORD"] == f'"{password}"'
    for name in SCALED_HUBS:
        hub = services[name]["environment"]
        assert hub["GCS_BUS_PASSWORD"] == password
    with nats_server(password, config=Path(source)) as address:
        assert "Authorization Violation" in (login_refused(address) or "")
        wrong = login_refused(address, user=hub["GCS_BUS_USER"], password="not-the-password")
        assert "Authorization Violation" in (wrong or "")
        assert login_refused(address, user=hub["GCS_BUS_USER"], password=password) is None


def test_the_scaled_hubs_refuse_to_start_without_their_secrets(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """The scaled secrets are optional to compose (the default stack must not need
    them), so the hub itself refuses the empty ones in production."""
    from backend.settings import HubSettings

    monkeypatch.chdir(tmp_path)
    result = _config(COMPOSE_SECRETS)
    assert result.returncode == 0, result.stderr
    hub = yaml.safe_load(result.stdout)["services"]["hub-a"]
    for variable in list(os.environ):
        if variable.startswith("GCS_") or variable == "DATABASE_URL":
            monkeypatch.delenv(variable)
    for variable, value in hub["environment"].items():
        monkeypatch.setenv(variable, str(value))
    # Empty tokens are refused first; with tokens, the empty admin password is.
    with pytest.raises(ValidationError, match="GCS_AGENT_TOKENS must be vehicle=token pairs"):
        HubSettings()
    monkeypatch.setenv("GCS_AGENT_TOKENS", f"fleet_1={'f1' * 16}")
    with pytest.raises(ValidationError, match="refusing default secrets in production"):
        HubSettings()
    # ...and with a good admin password, the empty bus password is refused too.
    monkeypatch.setenv("GCS_ADMIN_PASSWORD", SCALED_SECRETS["SCALED_ADMIN_PASSWORD"])
    with pytest.raises(ValidationError, match="GCS_BUS_PASSWORD is a default"):
        HubSettings()


def test_the_scaled_proxy_sends_every_connection_to_the_two_hubs_with_websocket_upgrades() -> None:
    services = _scaled_services()
    proxy = services["proxy"]
    [mount] = [volume for volume in proxy["volumes"] if "nginx-scaled.conf" in str(volume)]
    source = mount["source"] if isinstance(mount, dict) else str(mount).split(":")[0]
    directives = _nginx_directives(Path(source).read_text())

    upstream_servers = {words[1] for words in directives if words[0] == "server" and len(words) > 1}
    hub_addresses = set()
    for name in SCALED_HUBS:
        command = services[name]["command"]
        hub_addresses.add(f"{name}:{command[command.index('--port') + 1]}")
    assert upstream_servers == hub_addresses
    assert ["proxy_pass", "http://gcs_hubs"] in directives
    assert ["proxy_http_version", "1.1"] in directives
    assert ["proxy_set_header", "Upgrade", "$http_upgrade"] in directives
    assert ["proxy_set_header", "Connection", "$connection_upgrade"] in directives
    # ...and the map that makes $connection_upgrade "upgrade" for an Upgrade request.
    assert ["map", "$http_upgrade", "$connection_upgrade"] in directives
    assert ["default", "upgrade"] in directives
    # The agents and the dashboards reach the hubs only through the proxy.
    [listen] = [words[1] for words in directives if words[0] == "listen"]
    for name in ("fleet-agent-1", "fleet-agent-2"):
        assert services[name]["environment"]["GCS_AGENT_HUB"] == f"ws://proxy:{listen}"
    for name in SCALED_HUBS:
        assert "ports" not in services[name]


# -- images, commands and volumes: what each service runs and where its state lives ----


def _mounts(service: dict[str, Any]) -> dict[str, str]:
    """A service's volumes as target -> source (compose v1 renders "source:target:mode",
    v2 a mapping)."""
    mounts = {}
    for volume in service.get("volumes", []):
        if isinstance(volume, dict):
            mounts[volume["target"]] = str(volume.get("source", ""))
        else:
            source, target = str(volume).split(":")[:2]
            mounts[target] = source
    return mounts


def _image_env() -> dict[str, dict[str, str]]:
    """Each Dockerfile target's environment, as its image has it."""
    from tests.packaging.image_build import env_values, parse

    envs = {}
    for target, stage in parse((ROOT / "Dockerfile").read_text()).items():
        env: dict[str, str] = {}
        for keyword, rest in stage.instructions:
            if keyword == "ENV":
                env.update(env_values(rest, env))
        envs[target] = env
    return envs


def test_every_service_that_keeps_state_keeps_it_in_a_named_volume() -> None:
    services = _scaled_services()
    declared = set(yaml.safe_load(_config({**COMPOSE_SECRETS, **SCALED_SECRETS}).stdout)["volumes"])
    envs = _image_env()
    state = {
        "hub": envs["hub"]["GCS_DATA_DIR"],
        # The outbox, onboard .tlogs and the health file are all in one folder.
        "agent": str(Path(envs["agent"]["GCS_AGENT_OUTBOX_DIR"]).parent),
    }
    assert Path(envs["agent"]["GCS_AGENT_TLOG_DIR"]).parent == Path(state["agent"])
    checked = set()
    for name, service in services.items():
        mounts = _mounts(service)
        if service.get("image", "").startswith("postgres"):
            folder = "/var/lib/postgresql/data"
        elif "build" in service and service["build"]["target"] in state:
            folder = state[service["build"]["target"]]
        else:
            continue
        assert mounts.get(folder) in declared, f"{name} keeps {folder} in no named volume"
        checked.add(name)
    assert checked == {
        "db",
        "hub",
        "agent-1",
        "agent-2",
        "scaled-db",
        "hub-a",
        "hub-b",
        "fleet-agent-1",
        "fleet-agent-2",
    }


def test_the_scaled_hubs_share_their_files_and_keep_their_spools_apart() -> None:
    services = _scaled_services()
    a, b = (_mounts(services[name]) for name in SCALED_HUBS)
    # Photos, mosaics, offline tiles and .tlogs: one folder, whichever hub took them.
    assert a["/data"] == b["/data"]
    # Each hub replays its own spool of rows kept through a database outage.
    spool = services["hub-a"]["environment"]["GCS_SPOOL_DIR"]
    assert a[spool] != b[spool]
    assert _mounts(services["hub"])["/data"] != a["/data"]  # the single hub is apart


def test_each_service_runs_a_command_its_image_understands() -> None:
    """Each service names a Dockerfile target, and its command parses with that role's
    own command line (the image's entrypoint before it)."""
    from gcs.cli import build_parser as gcs_parser
    from simulator.config import parse_args as simulator_args
    from tests.packaging.image_build import parse
    from vehicle_agents.cli import build_parser as agent_parser

    targets = set(parse((ROOT / "Dockerfile").read_text()))
    roles = {}
    for name, service in _scaled_services().items():
        if "build" not in service:
            continue
        target = service["build"]["target"]
        assert target in targets, f"{name}: no target {target!r} in the Dockerfile"
        roles[name] = target
        command = [str(word) for word in service["command"]]
        if target == "hub":
            assert command[:3] == ["python", "-m", "gcs"]
            assert gcs_parser().parse_args(command[3:]).command == "hub"
        elif target == "agent":
            agent_parser().parse_args(command)
        else:
            simulator_args(command)
    assert set(roles.values()) == {"hub", "agent", "simulator"}


def test_the_deployment_guide_names_every_volume_and_image() -> None:
    """docs/deploy.md tells a deployer where each piece of state lives and which image
    runs what: it names every named volume and every image of the compose file."""
    rendered = yaml.safe_load(_config({**COMPOSE_SECRETS, **SCALED_SECRETS}).stdout)
    guide = (ROOT / "docs" / "deploy.md").read_text()
    for volume in rendered["volumes"]:
        assert f"`{volume}`" in guide, volume
    for service in rendered["services"].values():
        if "build" in service:
            assert f"`{service['image'].partition(':')[0]}`" in guide, service["image"]
            assert f"`{service['build']['target']}`" in guide
