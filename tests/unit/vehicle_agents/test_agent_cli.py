"""The agent's settings have one name each, in the file, the flags and the environment,
and a mistake in them is answered with what to do."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.docs import page_holding
from vehicle_agents.cli import build_parser, overrides_from
from vehicle_agents.config import (
    ENV_PREFIX,
    AgentSettings,
    SettingsError,
    flag_for,
    load_agent_settings,
)
from vehicle_agents.fcu.modes import _VEHICLE_TYPE_NAMES

ROOT = Path(__file__).resolve().parents[3]


def _empty_config(tmp_path: Path) -> Path:
    config = tmp_path / "agent.toml"
    config.write_text("")
    return config


def test_every_setting_has_a_flag_of_its_own_name() -> None:
    parser = build_parser()
    flags = {
        action.dest: action.option_strings
        for action in parser._actions
        if action.dest in AgentSettings.model_fields and action.help != "==SUPPRESS=="
    }
    assert set(flags) == set(AgentSettings.model_fields)
    for name, options in flags.items():
        assert options == [flag_for(name)], name
    assert flag_for("telemetry_rate_hz") == "--telemetry-rate-hz"


def test_the_flags_reach_the_settings_by_their_names(tmp_path: Path) -> None:
    args = build_parser().parse_args(
        [
            "--token",
            "t",
            "--telemetry-rate-hz",
            "4",
            "--hub-failsafe-action",
            "rtl",
            "--hub-failsafe-timeout-s",
            "20",
            "--stream-rates-hz",
            "ATTITUDE=20",
            "--mavlink-forward",
            "udpout:127.0.0.1:14550",
            "--source-system",
            "250",
        ]
    )
    settings = load_agent_settings(overrides_from(args), _empty_config(tmp_path))
    assert settings.telemetry_rate_hz == 4
    assert settings.hub_failsafe_action == "rtl"
    assert settings.hub_failsafe_timeout_s == 20
    assert settings.stream_rates_hz == {"ATTITUDE": 20}
    assert settings.mavlink_forward == ["udpout:127.0.0.1:14550"]
    assert settings.source_system == 250


def test_the_flags_of_earlier_releases_still_work(tmp_path: Path) -> None:
    args = build_parser().parse_args(
        [
            "--token",
            "t",
            "--telemetry-rate",
            "4",
            "--hub-failsafe",
            "hold",
            "--hub-failsafe-timeout",
            "30",
        ]
    )
    settings = load_agent_settings(overrides_from(args), _empty_config(tmp_path))
    assert (settings.telemetry_rate_hz, settings.hub_failsafe_action) == (4, "hold")
    assert settings.hub_failsafe_timeout_s == 30


def test_a_missing_token_names_the_flag_the_variable_and_the_key(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("GCS_AGENT_TOKEN", raising=False)
    config = tmp_path / "agent.toml"
    config.write_text('fcu = "/dev/ttyACM0,115200"\n')
    with pytest.raises(SettingsError) as refused:
        load_agent_settings({}, config)
    for way in ("--token", "GCS_AGENT_TOKEN", "`token = ...` in the config file"):
        assert way in str(refused.value)
    # ...but --print-id, which comes before enrolment, needs none.
    assert load_agent_settings({}, config, require_token=False).token is None


def test_an_unknown_key_gets_a_suggestion(tmp_path: Path) -> None:
    config = tmp_path / "agent.toml"
    config.write_text('token = "t"\ntelemetry_rate = 4\n')
    with pytest.raises(SettingsError, match="'telemetry_rate'; did you mean 'telemetry_rate_hz'"):
        load_agent_settings({}, config)


def _run_gcs(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "gcs", *args],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )


def test_the_command_line_explains_a_bad_setting(tmp_path: Path) -> None:
    env = {"PATH": "/usr/bin:/bin", "GCS_AGENT_TOKEN": "t"}
    done = _run_gcs("agent", "--config", str(tmp_path / "x.toml"), env=env)
    assert done.returncode == 2  # the file is missing: said, no traceback
    assert "Traceback" not in done.stderr
    config = tmp_path / "agent.toml"
    config.write_text("telemetry_rate_hz = 99\n")
    done = _run_gcs("agent", "--config", str(config), env=env)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert "telemetry_rate_hz: Input should be less than or equal to 50" in done.stderr
    assert "--telemetry-rate-hz, GCS_AGENT_TELEMETRY_RATE_HZ" in done.stderr


def test_gcs_hub_without_the_hub_extra_names_the_extra() -> None:
    """An agent-only install has neither uvicorn nor FastAPI; here they are made
    unimportable the way a missing package is (ModuleNotFoundError on import)."""
    script = (
        "import sys\n"
        "for name in ('uvicorn', 'fastapi', 'sqlalchemy'): sys.modules[name] = None\n"
        "from gcs.cli import main\n"
        "sys.exit(main(['hub']))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    assert "install the 'hub' extra" in done.stderr
    assert "fleet-gcs[hub]" in done.stderr


def test_a_toml_syntax_error_names_the_file_and_the_place(tmp_path: Path) -> None:
    config = tmp_path / "agent.toml"
    config.write_text('vehicle_id = "copter_1"\nfcu = "tcp:127.0.0.1:5760\n')
    done = subprocess.run(
        [sys.executable, "-m", "gcs", "agent", "--config", str(config), "--print-id"],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
        check=False,
    )
    assert done.returncode == 2
    assert f"{config}: not valid TOML: " in done.stderr
    assert "(at line 2, column 26)" in done.stderr
    assert "Traceback" not in done.stderr


def test_the_readme_lists_every_setting_by_its_one_name() -> None:
    """The table of the agent's settings (docs/reference.md): a row per setting, each naming the
    config key, the flag and the variable, and nothing else."""
    readme = page_holding("| key | flag | variable | default and meaning |").read_text()
    rows = re.findall(r"^\| `([a-z_]+)` \| `(--[a-z-]+)` \| `([A-Z_]+)` \|", readme, re.MULTILINE)
    assert rows, "the agent settings table is missing"
    assert [key for key, _, _ in rows] == list(AgentSettings.model_fields)
    for key, flag, variable in rows:
        assert (flag, variable) == (flag_for(key), f"{ENV_PREFIX}{key.upper()}")


def test_the_example_config_uses_known_keys_and_a_real_default_id(tmp_path: Path) -> None:
    """deploy/agent.toml.example, with its commented-out settings switched on, loads."""
    example = (ROOT / "deploy" / "agent.toml.example").read_text()
    switched_on = re.sub(r"^# ([a-z_]+ = )", r"\1", example, flags=re.MULTILINE)
    config = tmp_path / "agent.toml"
    config.write_text(switched_on)
    settings = load_agent_settings({}, config)
    assert settings.vehicle_id is not None
    # The example id has the form the agent gives itself by default.
    vehicle_type, _, machine = settings.vehicle_id.rpartition("_")
    assert vehicle_type in set(_VEHICLE_TYPE_NAMES.values())
    assert re.fullmatch(r"[0-9a-f]{4}", machine)
