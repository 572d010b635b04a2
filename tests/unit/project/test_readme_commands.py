"""The table of commands (the integrator's guide) names every command the protocol defines."""

from __future__ import annotations

import re
import typing

from protocol.messages import Command
from tests.support.docs import page_holding

TABLE_HEADER = "| `name` | fields |"


def _command_names() -> set[str]:
    union = typing.get_args(Command)[0]
    return {member.model_fields["name"].default for member in typing.get_args(union)}


def test_the_readme_lists_every_command() -> None:
    text = page_holding(TABLE_HEADER).read_text()
    table = text[text.index(TABLE_HEADER) :].split("\n\n", 1)[0]
    listed = set(re.findall(r"`([a-z_]+)`", table.split("| fields |", 1)[1]))
    missing = _command_names() - listed
    assert not missing, f"the command table lacks {sorted(missing)}"
    assert {"param_set", "mission_upload"} <= _command_names()
