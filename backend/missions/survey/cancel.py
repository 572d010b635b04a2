"""Stopping a survey plan part way: the planner is cooperative.

A plan runs in a worker thread (backend/surveys/planning.py), and a thread cannot be
killed: so the planner's loops call `checkpoint()`, which raises PlanStopped once the
plan's budget is stopped (its client went away, the hub is stopping) or past its deadline.
Each step between two checkpoints is bounded by the plan's limits (lanes, photos: see
limits.py), so a stopped plan ends within a step. Outside a budget (the unit tests, the
benchmarks) `checkpoint()` does nothing.

The budget travels in a context variable rather than as an argument through every
planner function: the planner stays pure and its signatures unchanged.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar


class PlanStopped(Exception):
    """The plan was stopped before it finished; `reason` says why (a metric's label)."""

    def __init__(self, reason: str) -> None:
        super().__init__(f"survey plan stopped: {reason}")
        self.reason = reason


class PlanBudget:
    """One plan's deadline (on `clock`) and stop flag. `stop` is called from the event
    loop's thread and read by the worker: a str assignment is atomic under the GIL."""

    def __init__(self, deadline: float, clock: Callable[[], float] = time.monotonic) -> None:
        self.deadline = deadline
        self._clock = clock
        self._stopped: str | None = None
        self.checks = 0  # checkpoints passed: how finely the planner can be stopped

    @property
    def stopped(self) -> str | None:
        return self._stopped

    def stop(self, reason: str) -> None:
        if self._stopped is None:
            self._stopped = reason

    def check(self) -> None:
        self.checks += 1
        if self._stopped is None and self._clock() > self.deadline:
            self._stopped = "timeout"
        if self._stopped is not None:
            raise PlanStopped(self._stopped)


_budget: ContextVar[PlanBudget | None] = ContextVar("survey_plan_budget", default=None)


def checkpoint() -> None:
    """Raise PlanStopped if the running plan was stopped or is past its deadline."""
    budget = _budget.get()
    if budget is not None:
        budget.check()


@contextmanager
def planning(budget: PlanBudget) -> Iterator[PlanBudget]:
    """Run the plan inside with `budget` (in the worker thread)."""
    token = _budget.set(budget)
    try:
        budget.check()  # stopped while it waited for a worker: do not start
        yield budget
    finally:
        _budget.reset(token)
