"""The run's setup and call times per test folder, printed at the end of every run (a
pytest plugin that the root conftest loads).

`--durations` names the slowest calls; it cannot say whether a folder's cost is in its
fixtures or its tests. The fast-suite bar (issue #31) is stated as a median setup per
integration test, so every run prints it: for each folder under tests/, the tests, the
median and the total of setup and call, and the total of the tests' own teardown.
"""

from __future__ import annotations

import statistics
from collections import defaultdict
from dataclasses import dataclass, field

import pytest


@dataclass
class _Phases:
    setup_s: list[float] = field(default_factory=list)
    call_s: list[float] = field(default_factory=list)
    teardown_s: float = 0.0


def _folder(nodeid: str) -> str:
    """``tests/integration/test_x.py::t`` -> ``integration``; a module at tests/ -> ``tests``."""
    parts = nodeid.split("::", 1)[0].split("/")
    return parts[1] if len(parts) > 2 else parts[0]


class _PhaseTimes:
    """Registered once per run by `pytest_configure`; pytest calls its hooks."""

    def __init__(self) -> None:
        self.folders: dict[str, _Phases] = defaultdict(_Phases)

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        phases = self.folders[_folder(report.nodeid)]
        if report.when == "setup":
            phases.setup_s.append(report.duration)
        elif report.when == "call":
            phases.call_s.append(report.duration)
        else:
            phases.teardown_s += report.duration

    def pytest_terminal_summary(self, terminalreporter: pytest.TerminalReporter) -> None:
        if not self.folders:
            return
        terminalreporter.section("setup and call per folder (s)")
        terminalreporter.line(
            f"{'folder':<12} {'tests':>6} {'setup median':>13} {'setup total':>12} "
            f"{'call median':>12} {'call total':>11} {'teardown':>9}"
        )
        for folder, phases in sorted(self.folders.items()):
            setups, calls = phases.setup_s or [0.0], phases.call_s or [0.0]
            terminalreporter.line(
                f"{folder:<12} {len(phases.setup_s):>6} {statistics.median(setups):>13.3f} "
                f"{sum(setups):>12.1f} {statistics.median(calls):>12.3f} "
                f"{sum(calls):>11.1f} {phases.teardown_s:>9.1f}"
            )


def pytest_configure(config: pytest.Config) -> None:
    config.pluginmanager.register(_PhaseTimes(), "phase-times")
