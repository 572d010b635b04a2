"""MAV_CMD and MAV_FRAME numbers are pymavlink's named constants in our code, never typed
by hand: a hand-typed 16 reads as nothing, and a typo in it is another command."""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
PACKAGES = ("backend", "vehicle_agents", "protocol", "simulator", "common", "gcs")
# Fields and variables that hold a MAV_CMD or a MAV_FRAME.
FIELD_NAMES = frozenset({"command", "frame", "cmd"})
COMMAND_NAME = re.compile(r"^_?(MAV_CMD|NAV|DO|CONDITION)_|_CMDS?$")
# A set or table of frames; a single number named so is as often a count of frames.
FRAMES_NAME = re.compile(r"FRAMES?$")


def _numbers(node: ast.expr) -> bool:
    """An int literal, or a collection (set, tuple, list, dict) of them."""
    if isinstance(node, ast.Constant):
        return type(node.value) is int
    if isinstance(node, ast.Set | ast.Tuple | ast.List):
        return bool(node.elts) and all(_numbers(e) for e in node.elts)
    if isinstance(node, ast.Dict):
        keys = [k for k in node.keys if k is not None]
        return bool(keys) and all(_numbers(k) for k in keys)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
        return node.func.id in {"frozenset", "set"} and all(_numbers(a) for a in node.args)
    return False


def _field(node: ast.expr) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return None


def _targets(node: ast.Assign | ast.AnnAssign) -> list[str]:
    targets = node.targets if isinstance(node, ast.Assign) else [node.target]
    names: list[str] = []
    for target in targets:
        parts = target.elts if isinstance(target, ast.Tuple) else [target]
        names += [name for part in parts if (name := _field(part)) is not None]
    return names


def hand_typed(source: str) -> Iterator[tuple[int, str]]:
    """(line, what) for each MAV_CMD or MAV_FRAME number typed by hand in ``source``."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.keyword) and node.arg in FIELD_NAMES and _numbers(node.value):
            yield node.value.lineno, f"{node.arg}={ast.unparse(node.value)}"
        elif isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
            if any(_field(o) in FIELD_NAMES for o in operands) and any(map(_numbers, operands)):
                yield node.lineno, ast.unparse(node)
        elif isinstance(node, ast.Assign | ast.AnnAssign) and node.value is not None:
            if not _numbers(node.value):
                continue
            names = [n.upper() for n in _targets(node)]
            single = isinstance(node.value, ast.Constant)
            if any(
                COMMAND_NAME.search(n)
                or n.startswith("MAV_FRAME")
                or (FRAMES_NAME.search(n) and not single)
                for n in names
            ):
                yield node.lineno, ast.unparse(node)


def _sources() -> list[Path]:
    return sorted(p for package in PACKAGES for p in (ROOT / package).rglob("*.py"))


@pytest.mark.parametrize("path", _sources(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_hand_typed_mav_cmd_or_frame(path: Path) -> None:
    found = [f"line {line}: {what}" for line, what in hand_typed(path.read_text())]
    assert not found, f"use pymavlink's named constants (mavlink2.MAV_CMD_...): {found}"


@pytest.mark.parametrize(
    "source",
    [
        "NAV_WAYPOINT, NAV_LAND = 16, 21",
        "AMSL_FRAMES = {0, 5}",
        "_PLAIN_FRAME = {5: 0, 6: 3}",
        "item = MissionItem(command=16, frame=0)",
        "ok = item.command == 22",
        "ok = item.frame in (0, 5)",
    ],
)
def test_the_check_sees_hand_typed_numbers(source: str) -> None:
    assert list(hand_typed(source))


def test_the_check_lets_named_constants_and_other_numbers_through() -> None:
    source = (
        "AMSL_FRAMES = frozenset({mavlink2.MAV_FRAME_GLOBAL})\n"
        "item = MissionItem(command=mavlink2.MAV_CMD_NAV_WAYPOINT, seq=0)\n"
        "MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME = 9\n"
        "self.bad_frames = 0\n"
        "ok = item.seq == 1\n"
    )
    assert list(hand_typed(source)) == []
