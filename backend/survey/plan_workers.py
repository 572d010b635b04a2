"""Survey plans and area files' parsing, computed in worker processes (backend/worker_pool.py):
bounded in number and time, and stopped when nobody waits for them any more.

Why processes: planning and XML parsing are Python loops that hold the GIL; in threads of
the hub's process the event loop waited for them at each turn (`/health` p99 170 ms under
a flood of previews, 234 ms under one of imports; docs/deployer.md "The hub under floods"). Every
plan is estimated first and refused past the hub's limits (limits.py) inside the worker,
so what is left to bound is time and number: a plan past `survey_plan_timeout_s`, whose
client went away, or whose request was cancelled (the hub is stopping), has its worker
killed at once, wherever it is (GEOS, numpy).

At most `survey_plan_workers` plans run at once and `survey_plan_max_pending` run or wait;
beyond, a 429 with Retry-After. Imports alike: one worker, `survey_import_max_pending`,
`survey_import_timeout_s`. The plan comes back as JSON of `SurveyPlan` (pydantic reads it
in Rust: a 549-item mission's plan costs the event loop about 2 ms, where the
planner's own objects took 50 ms to unpickle). On /metrics: plans running or waiting now,
and plans stopped before they finished by reason.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Awaitable, Callable

from pydantic import TypeAdapter

from backend.errors import GcsError, InvalidRequest
from backend.observability import metrics
from backend.settings import HubSettings
from backend.survey.files.areas import read_area_file
from backend.survey.files.items import InteropError, TooManyVertices
from backend.survey.planning.camera import CameraError
from backend.survey.planning.limits import SurveyLimits
from backend.survey.planning.planner import PlanError
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet, SurveyPlan, plan_survey, summary
from backend.worker_pool import JobStopped, WorkerPool

log = logging.getLogger(__name__)

# Made only once the plan starts: a request refused before it never watches its client.
ClientWatch = Callable[[], Awaitable[object]]
# What the fork server imports once, so that each worker it forks has them already.
PRELOAD = ("backend.survey.plan_workers",)
_PLAN_JSON = TypeAdapter(SurveyPlan)
# The pool's reasons as /metrics has long named them.
_STOP_REASONS = {"gone": "disconnect", "timeout": "timeout", "cancelled": "shutdown"}


class ClientGone(GcsError):
    """The client closed the connection before its plan was ready (nginx's 499: nobody
    reads it)."""

    status_code = 499


class HubStopping(GcsError):
    status_code = 503


class WorkerDied(GcsError):
    """A worker process that ended before it answered (out of memory, a crash)."""

    status_code = 503


def plan_json(request: SurveyRequest, fleet: list[Fleet], limits: SurveyLimits) -> bytes:
    """In a worker: the plan, as JSON of SurveyPlan."""
    return _PLAN_JSON.dump_json(summary(plan_survey(request, fleet, limits)))


def area_file_json(kind: str, text: str, max_vertices: int) -> bytes:
    """In a worker: a survey request's fields from an area file, as JSON."""
    fields = read_area_file(kind, text, max_vertices)
    return json.dumps(fields, allow_nan=False, separators=(",", ":")).encode()


class SurveyPlanner:
    def __init__(self, settings: HubSettings) -> None:
        self._settings = settings
        self.limits = SurveyLimits(
            survey_max_lanes=settings.survey_max_lanes,
            survey_max_photos=settings.survey_max_photos,
            survey_max_mission_items=settings.survey_max_mission_items,
        )
        self.pool = WorkerPool(
            workers=settings.survey_plan_workers,
            max_pending=settings.survey_plan_max_pending,
            what="survey plans",
            setting="survey_plan_max_pending",
            preload=PRELOAD,
        )
        self.import_pool = WorkerPool(
            workers=1,
            max_pending=settings.survey_import_max_pending,
            what="survey area imports",
            setting="survey_import_max_pending",
            preload=PRELOAD,
        )

    async def plan(
        self, request: SurveyRequest, fleet: list[Fleet], gone: ClientWatch | None = None
    ) -> SurveyPlan:
        """The survey's plan, its errors as 422s naming the field or limit; what `gone`
        returns finishes when the client has gone away, which stops the plan."""
        self.pool.check_room()  # before `gone()` is made: a refused request never watches
        timeout = self._settings.survey_plan_timeout_s
        metrics.SURVEY_PLANS_RUNNING.inc()
        try:
            data = await self.pool.run(
                timeout,
                plan_json,
                request,
                fleet,
                self.limits,
                gone=None if gone is None else gone(),
            )
        except JobStopped as stopped:
            reason = _STOP_REASONS.get(stopped.reason, stopped.reason)
            metrics.SURVEY_PLANS_STOPPED.labels(reason=reason).inc()
            log.info("survey plan stopped: %s", reason)
            if stopped.reason == "timeout":
                raise _timed_out(timeout) from None
            if stopped.reason == "gone":
                raise ClientGone("the client closed the connection; its plan was stopped") from None
            if stopped.reason == "cancelled":
                raise HubStopping("the hub is stopping; the plan was stopped") from None
            raise WorkerDied(f"the survey planner's worker {stopped.message}") from None
        except CameraError as exc:
            raise InvalidRequest("camera", str(exc)) from exc
        except PlanError as exc:
            raise InvalidRequest("area", str(exc)) from exc
        finally:
            metrics.SURVEY_PLANS_RUNNING.dec()
        return _PLAN_JSON.validate_json(data)

    async def read_area_file(self, kind: str, text: str) -> bytes:
        """A survey request's fields from an area file, as JSON; 422s naming the problem."""
        settings = self._settings
        timeout = settings.survey_import_timeout_s
        try:
            return await self.import_pool.run(
                timeout, area_file_json, kind, text, settings.survey_import_max_vertices
            )
        except JobStopped as stopped:
            if stopped.reason != "timeout":
                raise WorkerDied(f"the area file's worker {stopped.message}") from None
            raise InvalidRequest(
                "content",
                f"the file took longer than {timeout:g} s to read, the limit "
                "(survey_import_timeout_s)",
            ) from None
        except TooManyVertices as error:
            raise InvalidRequest(
                "content",
                f"the file's area has {error.count:,} vertices; the limit is {error.limit:,} "
                "(survey_import_max_vertices)",
            ) from error
        except InteropError as error:
            raise InvalidRequest("content", str(error)) from error
        except ValueError as error:  # a NaN (QGC writes null for one) cannot be JSON
            raise InvalidRequest(
                "content", f"the file holds a value that is not a number: {error}"
            ) from error

    def close(self) -> None:
        """Kill every worker (the hub is stopping): their plans end as 503s."""
        self.pool.close()
        self.import_pool.close()


def _timed_out(timeout_s: float) -> InvalidRequest:
    return InvalidRequest(
        "area",
        f"the plan took longer than {timeout_s:g} s, the limit (survey_plan_timeout_s); "
        "fly higher, survey a smaller area or choose fewer drones",
    )
