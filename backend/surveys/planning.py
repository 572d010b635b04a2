"""Survey plans computed off the event loop, bounded in number and time, and stopped when
nobody waits for them any more.

Why threads and a cooperative planner rather than a process pool: every plan is estimated
first and refused past the hub's limits (backend/missions/survey/limits.py), so what is
left to bound is time, and the planner checks its budget in its loops (cancel.py): a plan
whose client went away, that is past `survey_plan_timeout_s`, or that the hub's shutdown
stops, ends within one step. A thread shares the hub's memory (no second copy of numpy and
shapely per worker, no pickling of plans), and cannot outlive the hub: a worker process
can, and did (a planner left at 9 GB after `gcs demo` stopped). The planner's numpy and
GEOS calls release the GIL, and its Python loops give it up every few milliseconds, so
the event loop keeps answering while plans run.

At most `survey_plan_workers` plans run at once and `survey_plan_max_pending` run or wait;
beyond, a 429 with Retry-After. The figures are on /metrics: plans running now, and plans
stopped before they finished by reason.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Awaitable, Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from backend.errors import GcsError, InvalidRequest, RateLimited
from backend.missions.survey.camera import CameraError
from backend.missions.survey.cancel import PlanBudget, PlanStopped, planning
from backend.missions.survey.limits import SurveyLimits
from backend.missions.survey.planner import PlanError
from backend.missions.survey.schemas import SurveyRequest
from backend.missions.survey.service import Fleet, Survey, plan_survey
from backend.observability import metrics
from backend.settings import HubSettings

log = logging.getLogger(__name__)

# Made only once the plan starts: a request refused before it never watches its client.
ClientWatch = Callable[[], Awaitable[object]]


class ClientGone(GcsError):
    """The client closed the connection before its plan was ready (nginx's 499: nobody
    reads it)."""

    status_code = 499


class HubStopping(GcsError):
    status_code = 503


class SurveyPlanner:
    def __init__(self, settings: HubSettings) -> None:
        self._settings = settings
        self.limits = SurveyLimits(
            survey_max_lanes=settings.survey_max_lanes,
            survey_max_photos=settings.survey_max_photos,
            survey_max_mission_items=settings.survey_max_mission_items,
        )
        self._executor = ThreadPoolExecutor(
            max_workers=settings.survey_plan_workers, thread_name_prefix="survey-plan"
        )
        self._budgets: set[PlanBudget] = set()  # plans running or waiting for a worker

    async def plan(
        self, request: SurveyRequest, fleet: list[Fleet], gone: ClientWatch | None = None
    ) -> Survey:
        """The survey's plan, its errors as 422s naming the field or limit; what `gone`
        returns finishes when the client has gone away, which stops the plan."""
        if len(self._budgets) >= self._settings.survey_plan_max_pending:
            raise RateLimited(
                f"{len(self._budgets)} survey plans are running or waiting, the most "
                f"(survey_plan_max_pending); try again in 1 s",
                1.0,
            )
        timeout = self._settings.survey_plan_timeout_s
        budget = PlanBudget(time.monotonic() + timeout)
        self._budgets.add(budget)
        work = asyncio.get_running_loop().run_in_executor(
            self._executor, self._run, budget, request, fleet
        )

        def finished(done: asyncio.Future[Survey]) -> None:
            # The worker ends on its own once stopped; its outcome is then nobody's.
            self._budgets.discard(budget)
            if not done.cancelled():
                done.exception()  # retrieved: no "never retrieved" warning

        work.add_done_callback(finished)
        waiting: set[asyncio.Future[Any]] = {work}
        watcher = None if gone is None else asyncio.ensure_future(gone())
        if watcher is not None:
            waiting.add(watcher)
        try:
            done, _ = await asyncio.wait(
                waiting, timeout=timeout, return_when=asyncio.FIRST_COMPLETED
            )
        except asyncio.CancelledError:  # the request's task: the server is stopping
            budget.stop("shutdown")
            raise
        finally:
            if watcher is not None:
                watcher.cancel()
        if work not in done:
            budget.stop("disconnect" if watcher in done else "timeout")
            if watcher in done:
                raise ClientGone("the client closed the connection; its plan was stopped")
            raise _timed_out(timeout)
        try:
            return work.result()
        except PlanStopped as stopped:
            if stopped.reason == "timeout":
                raise _timed_out(timeout) from None
            raise HubStopping("the hub is stopping; the plan was stopped") from None
        except CameraError as exc:
            raise InvalidRequest("camera", str(exc)) from exc
        except PlanError as exc:
            raise InvalidRequest("area", str(exc)) from exc

    def _run(self, budget: PlanBudget, request: SurveyRequest, fleet: list[Fleet]) -> Survey:
        metrics.SURVEY_PLANS_RUNNING.inc()
        try:
            with planning(budget):
                return plan_survey(request, fleet, self.limits)
        except PlanStopped as stopped:
            metrics.SURVEY_PLANS_STOPPED.labels(reason=stopped.reason).inc()
            log.info("survey plan stopped after %d checkpoints: %s", budget.checks, stopped)
            raise
        finally:
            metrics.SURVEY_PLANS_RUNNING.dec()

    def close(self) -> None:
        """Stop every plan (the hub is stopping); the workers end within a step."""
        for budget in list(self._budgets):
            budget.stop("shutdown")
        with contextlib.suppress(RuntimeError):
            self._executor.shutdown(wait=False, cancel_futures=True)


def _timed_out(timeout_s: float) -> InvalidRequest:
    return InvalidRequest(
        "area",
        f"the plan took longer than {timeout_s:g} s, the limit (survey_plan_timeout_s); "
        "fly higher, survey a smaller area or choose fewer drones",
    )
