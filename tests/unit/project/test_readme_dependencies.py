"""The deployer's guide's list of the agent's base dependencies is pyproject.toml's."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from tests.support.docs import page_holding

ROOT = Path(__file__).parents[3]
LEAD_IN = "The agent needs only the base dependencies ("


def test_the_readme_names_every_base_dependency_and_no_other() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    base = {canonicalize_name(Requirement(line).name) for line in project["dependencies"]}
    text = " ".join(page_holding(LEAD_IN).read_text().split())
    assert LEAD_IN in text, f"the docs no longer say {LEAD_IN!r}"
    listed_text = text[text.index(LEAD_IN) + len(LEAD_IN) :].split(")", 1)[0]
    listed = {canonicalize_name(name) for name in re.split(r",\s*|\s+and\s+", listed_text)}
    assert listed == base, (
        f"the docs lack {sorted(base - listed)}, names {sorted(listed - base)} that are not "
        "base dependencies"
    )
