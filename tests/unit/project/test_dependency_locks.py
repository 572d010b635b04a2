"""The locks in requirements/ hold what pyproject.toml asks for (scripts/lock.sh writes them)."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[3]
PROJECT = "fleet-gcs"
# lock file -> the extras it installs on top of the base dependencies
LOCKS = {"agent": (), "hub": ("hub",), "simulator": ("simulator",), "dev": ("dev",)}
PIN = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==([^\s;\\]+)", re.MULTILINE)


def _requirements(extras: tuple[str, ...]) -> list[Requirement]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    wanted = [Requirement(spec) for spec in project["dependencies"]]
    pending = list(extras)
    while pending:
        for spec in project["optional-dependencies"][pending.pop()]:
            requirement = Requirement(spec)
            if canonicalize_name(requirement.name) == PROJECT:  # e.g. fleet-gcs[hub]
                pending.extend(requirement.extras)
            else:
                wanted.append(requirement)
    return wanted


def _pins(lock: str) -> dict[str, str]:
    text = (ROOT / "requirements" / f"{lock}.txt").read_text()
    return {canonicalize_name(name): version for name, version in PIN.findall(text)}


@pytest.mark.parametrize(("lock", "extras"), LOCKS.items())
def test_each_lock_pins_every_dependency_within_its_bounds(
    lock: str, extras: tuple[str, ...]
) -> None:
    pins = _pins(lock)
    stale = []
    for requirement in _requirements(extras):
        pinned = pins.get(canonicalize_name(requirement.name))
        if pinned is None or not requirement.specifier.contains(pinned, prereleases=True):
            stale.append(f"{requirement} (locked: {pinned or 'missing'})")
    assert not stale, (
        f"requirements/{lock}.txt does not match pyproject.toml: {stale}; run scripts/lock.sh"
    )


def test_the_locks_agree_on_every_shared_package() -> None:
    agent, hub, simulator, dev = (_pins(lock) for lock in LOCKS)
    assert agent.items() <= hub.items(), "run scripts/lock.sh"
    assert agent.items() <= simulator.items() <= hub.items(), "run scripts/lock.sh"
    assert hub.items() <= dev.items(), "run scripts/lock.sh"
