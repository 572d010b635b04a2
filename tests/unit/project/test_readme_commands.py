"""The README's table of commands names every command the protocol defines."""

from __future__ import annotations

import re
import typing
from pathlib import Path

from protocol.messages import Command

README = Path(__file__).parents[3] / "README.md"


def _command_names() -> set[str]:
    union = typing.get_args(Command)[0]
    return {member.model_fields["name"].default for member in typing.get_args(union)}


def test_the_readme_lists_every_command() -> None:
    text = README.read_text()
    table = text[text.index("| `name` | fields |") :].split("\n\n", 1)[0]
    listed = set(re.findall(r"`([a-z_]+)`", table.split("| fields |", 1)[1]))
    missing = _command_names() - listed
    assert not missing, f"README's command table lacks {sorted(missing)}"
    assert {"param_set", "mission_upload"} <= _command_names()
