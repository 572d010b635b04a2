"""The agent's LIDAR settings and probe command refuse what they cannot use, clearly."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from vehicle_agents.cli import main
from vehicle_agents.config import AgentSettings


def test_an_unknown_lidar_model_is_refused_naming_the_known_ones() -> None:
    with pytest.raises(ValidationError, match=r"unknown LIDAR model 'rplidar-a9'.*ld06"):
        AgentSettings(lidar="/dev/ttyUSB0", lidar_model="rplidar-a9")
    settings = AgentSettings(lidar="/dev/ttyUSB0", lidar_model="stl27l")
    assert settings.lidar_baud is None  # the model's: 921600


def test_the_probe_names_a_port_it_cannot_open(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["lidar-probe", "/dev/does-not-exist"]) == 2
    assert "cannot open /dev/does-not-exist" in capsys.readouterr().err
