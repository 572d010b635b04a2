from __future__ import annotations

from pathlib import Path

import pytest

from vehicle_agents.config import default_vehicle_id, hub_http_base, load_agent_settings


def test_flags_beat_environment_beat_config_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    config = tmp_path / "agent.toml"
    config.write_text(
        'fcu = "/dev/ttyACM0,115200"\nhub = "ws://file:8000"\n'
        'token = "from-file"\ntelemetry_rate_hz = 4\n'
    )
    monkeypatch.setenv("GCS_AGENT_HUB", "ws://env:8000")
    monkeypatch.setenv("GCS_AGENT_TELEMETRY_RATE_HZ", "5")
    settings = load_agent_settings({"telemetry_rate_hz": 7, "fcu": None}, config)
    assert settings.fcu == "/dev/ttyACM0,115200"  # only in the file
    assert settings.hub == "ws://env:8000/api/v1/agent/ws"  # environment over file
    assert settings.telemetry_rate_hz == 7  # flag over environment
    assert settings.token.get_secret_value() == "from-file"


def test_unknown_keys_in_the_config_file_are_refused(tmp_path: Path) -> None:
    config = tmp_path / "agent.toml"
    config.write_text('token = "t"\nfuc = "typo"\n')
    with pytest.raises(ValueError, match="fuc"):
        load_agent_settings({}, config)


def test_default_identity_uses_the_machine_id(tmp_path: Path) -> None:
    machine_id = tmp_path / "machine-id"
    machine_id.write_text("3fa2b9c0d1e2f3a4b5c6d7e8f9a0b1c2\n")
    assert default_vehicle_id("multirotor", machine_id) == "multirotor_3fa2"
    assert hub_http_base("wss://gcs.example.org/api/v1/agent/ws") == "https://gcs.example.org"
