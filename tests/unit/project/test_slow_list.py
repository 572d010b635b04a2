"""The slow-test budget: the list of slow tests (docs/reference.md) is the tests marked slow, each
with a reason, and an unmarked test over the budget fails."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

from tests.support.budget import BUDGET_VARIABLE, REPO, listed_slow, marked_slow


def test_the_readme_lists_exactly_the_tests_marked_slow_each_with_a_reason() -> None:
    listed = listed_slow()
    assert set(listed) == marked_slow(), (
        "docs/reference.md's Slow tests and the @pytest.mark.slow marks differ: "
        f"listed but not marked {sorted(set(listed) - marked_slow())}, "
        f"marked but not listed {sorted(marked_slow() - set(listed))}"
    )
    assert all(reason.strip() for reason in listed.values())


def test_an_unmarked_test_over_the_budget_is_named_and_far_over_it_fails(tmp_path: Path) -> None:
    (tmp_path / "test_timed.py").write_text(
        "import time\n"
        "import pytest\n"
        "def test_quick():\n    pass\n"
        "def test_over():\n    time.sleep(2.5)\n"
        "def test_a_little_over():\n    time.sleep(1.2)\n"
        "@pytest.mark.slow\n"
        "def test_over_but_marked():\n    time.sleep(2.5)\n"
    )
    result = subprocess.run(
        [
            *(sys.executable, "-m", "pytest", "-p", "tests.support.budget"),
            *("-p", "no:cacheprovider", "-o", "markers=slow: slow", "-q", str(tmp_path)),
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        env={"PYTHONPATH": str(REPO), BUDGET_VARIABLE: "1", "PATH": "/usr/bin:/bin"},
        timeout=120,
    )
    assert "1 failed, 3 passed" in result.stdout, result.stdout + result.stderr
    assert re.search(r"test_over took [0-9.]+ s \(setup [0-9.]+ s, call [0-9.]+ s\)", result.stdout)
    assert (
        "over the suite's 1 s budget for a test that is not marked slow. Make it" in result.stdout
    )
    summary = result.stdout.split("over the slow-test budget, not marked slow", 1)[1]
    assert re.search(r"test_a_little_over took 1\.[0-9] s", summary), result.stdout
    assert "test_over_but_marked" not in summary
