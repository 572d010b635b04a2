"""The agent's camera settings: refused before flight when they cannot work."""

from __future__ import annotations

from pathlib import Path

import pytest
from pydantic import ValidationError

from vehicle_agents.config import SettingsError, load_agent_settings


def empty(folder: Path) -> Path:
    """A config file with nothing in it (not the machine's /etc/gcs/agent.toml)."""
    path = folder / "agent.toml"
    path.write_text("")
    return path


def test_a_camera_needs_a_folder_for_its_photos(tmp_path: Path) -> None:
    with pytest.raises(SettingsError, match="--photo-dir"):
        load_agent_settings({"camera": "opencv:0", "token": "t"}, empty(tmp_path))
    settings = load_agent_settings(
        {"camera": "opencv:0", "token": "t", "outbox_dir": tmp_path}, empty(tmp_path)
    )
    assert settings.photo_folder() == tmp_path / "photos"


@pytest.mark.parametrize(
    ("setting", "value", "message"),
    [
        ("camera", "usb:0", "sim\\+http://HOST:PORT"),
        ("camera_model", "13.2,8.8,5472,3648", "sensor width,height"),
        ("camera_model", "13.2,8.8,5472,-3,8.8", "sensor width,height"),
    ],
)
def test_a_camera_the_agent_cannot_use_is_refused_with_the_form_it_takes(
    tmp_path: Path, setting: str, value: str, message: str
) -> None:
    with pytest.raises(ValidationError, match=message):
        load_agent_settings({setting: value, "token": "t", "photo_dir": tmp_path}, empty(tmp_path))
