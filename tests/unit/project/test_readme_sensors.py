"""The sensor table (the reference guide) is the agent's model table: every model, its default baud
rate, and nothing the agent does not read."""

from __future__ import annotations

import re

from tests.support.docs import page_holding
from vehicle_agents.sensors.lidar.models import MODELS


def test_the_sensor_table_lists_each_model_and_its_default_baud() -> None:
    text = page_holding("### Sensors").read_text()
    section = text[text.index("### Sensors") :]
    section = section[: section.index("\n## ")]
    rows = {
        match[1]: match[2]
        for match in re.finditer(r"^\| [^|]+ \| `([a-z0-9-]+)` \| [^|]+ \| (\d+)", section, re.M)
    }
    assert rows == {name: str(model.baud) for name, model in MODELS.items()}
