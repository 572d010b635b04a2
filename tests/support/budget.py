"""The suite's slow-test budget (docs/reference.md, "Slow tests"), a pytest plugin that the root
conftest loads.

A test whose setup and call together take longer than `budget_s()` is named in the run's
summary, and fails beyond `FAIL_FACTOR` times the budget, unless it is marked
``@pytest.mark.slow`` (on the function, or ``pytestmark`` for a module) and the
list of slow tests in docs/reference.md names it (its node id, or its module for a module-wide mark)
with the reason. `tests/unit/project/test_slow_list.py` checks that list against the marks.
"""

from __future__ import annotations

import ast
import os
import re
from collections.abc import Generator
from pathlib import Path

import pytest

from tests.support.docs import page_holding

BUDGET_S = 20.0
# A machine much slower or busier than the 2-core reference can widen the budget; CI
# keeps the default.
BUDGET_VARIABLE = "GCS_TEST_BUDGET_S"
REPO = Path(__file__).resolve().parents[2]
SLOW_LIST_HEADING = "### Slow tests"

# A busy or slower machine stretches every test alike: an unmarked test between the
# budget and FAIL_FACTOR times it is named in the run's summary (fix it or mark it);
# beyond, it fails. A hard line at the budget itself failed whole CI runs for a test that
# took 21 s on a machine where it usually takes 15.
FAIL_FACTOR = 2.0

_SETUP_S = pytest.StashKey[float]()
_OVER_BUDGET = pytest.StashKey[list[str]]()


def budget_s() -> float:
    return float(os.environ.get(BUDGET_VARIABLE, BUDGET_S))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    report = yield
    record(item, report)
    return report


def record(item: pytest.Item, report: pytest.TestReport) -> None:
    """Each phase's report: a passed call over the budget, without the ``slow`` mark, is
    named in the run's summary; over `FAIL_FACTOR` times the budget it becomes a failure
    that says what to do."""
    if report.when == "setup":
        item.stash[_SETUP_S] = report.duration
        return
    if report.when != "call" or not report.passed or item.get_closest_marker("slow"):
        return
    setup_s = item.stash.get(_SETUP_S, 0.0)
    total_s = setup_s + report.duration
    if total_s <= budget_s():
        return
    timing = (
        f"{item.nodeid} took {total_s:.1f} s (setup {setup_s:.1f} s, call "
        f"{report.duration:.1f} s), over the suite's {budget_s():g} s budget for a test "
        "that is not marked slow"
    )
    if total_s <= FAIL_FACTOR * budget_s():
        item.config.stash.setdefault(_OVER_BUDGET, []).append(timing)
        return
    report.outcome = "failed"
    report.longrepr = (
        f"{timing}. Make it faster (tests/README.md), or mark it "
        "@pytest.mark.slow and add it with its reason to the list of slow tests in "
        "docs/reference.md."
    )


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    over = terminalreporter.config.stash.get(_OVER_BUDGET, [])
    if over:
        terminalreporter.section("over the slow-test budget, not marked slow")
        for line in over:
            terminalreporter.line(line)


def marked_slow(tests_dir: Path = REPO / "tests") -> set[str]:
    """What carries the ``slow`` mark in the source: a module's path (``pytestmark``) or
    a test's node id without parameters (``@pytest.mark.slow`` on the function)."""
    found: set[str] = set()
    for path in sorted(tests_dir.rglob("test_*.py")):
        module = path.relative_to(REPO).as_posix()
        tree = ast.parse(path.read_text(), str(path))
        for node in tree.body:
            if isinstance(node, ast.Assign) and any(
                isinstance(target, ast.Name) and target.id == "pytestmark"
                for target in node.targets
            ):
                if _names_slow(node.value):
                    found.add(module)
            elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and any(
                _names_slow(decorator) for decorator in node.decorator_list
            ):
                found.add(f"{module}::{node.name}")
    return found


def _names_slow(node: ast.expr) -> bool:
    """``pytest.mark.slow`` or ``pytest.mark.slow(...)`` anywhere in the expression."""
    return any(
        isinstance(inner, ast.Attribute)
        and inner.attr == "slow"
        and isinstance(inner.value, ast.Attribute)
        and inner.value.attr == "mark"
        for inner in ast.walk(node)
    )


def listed_slow(page: Path | None = None) -> dict[str, str]:
    """The list of slow tests (on the page that holds it, docs/reference.md): each row's
    module or node id and its reason."""
    text = (page or page_holding(SLOW_LIST_HEADING)).read_text()
    start = text.index(SLOW_LIST_HEADING)
    section = text[start : text.find("\n#", start + len(SLOW_LIST_HEADING))]
    rows = re.findall(r"^\| `(tests/[^`]+)` \| (.+?) \|$", section, re.MULTILINE)
    return dict(rows)
