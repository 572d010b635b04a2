"""The first chunk's metadata (``X-Photo-Meta``) read, and the survey a photo belongs to.

Both are decided before the image's megabytes follow: a photo with no pose or with
metadata that does not parse is refused with the reason's code, and a photo is given
the survey its metadata names, else the one its vehicle was flying.
"""

from __future__ import annotations

import time
from collections.abc import Awaitable, Callable

from pydantic import ValidationError

from backend.errors import NotFound
from backend.imagery.photos.checks import Refusal, Refused
from backend.survey.flight.run import CLOCK_SLACK_S, SurveyRun
from protocol.photos import MAX_PHOTO_BYTES, PhotoMeta

ActiveSurveys = Callable[[], list[SurveyRun]]
FindSurvey = Callable[[str], Awaitable[SurveyRun]]


def parse_meta(photo_id: str, meta_json: str | None) -> PhotoMeta:
    """The metadata of photo ``photo_id``, or Refused with the code that says why not."""
    if meta_json is None:
        raise Refused(
            Refusal.BAD_METADATA,
            "the first chunk (offset 0) must carry the photo's metadata as "
            "JSON in the X-Photo-Meta header",
        )
    try:
        meta = PhotoMeta.model_validate_json(meta_json)
    except ValidationError as error:
        problems = error.errors()
        fields = {str(p["loc"][0]) for p in problems if p["loc"]}
        text = "; ".join(
            f"{'.'.join(str(part) for part in p['loc'])}: {p['msg']}" for p in problems[:5]
        )
        if "pose" in fields:
            code = Refusal.NO_POSE
        elif fields == {"size_bytes"} and any(p["type"] == "less_than_equal" for p in problems):
            code = Refusal.TOO_LARGE
            text = f"the photo is larger than the {MAX_PHOTO_BYTES} bytes a photo may be"
        else:
            code = Refusal.BAD_METADATA
        raise Refused(
            code, f"{code.value}: {text}", 413 if code is Refusal.TOO_LARGE else 422
        ) from None
    if meta.photo_id != photo_id:
        raise Refused(
            Refusal.BAD_METADATA,
            f"the metadata names photo {meta.photo_id}, the address {photo_id}",
        )
    return meta


class SurveyOfPhoto:
    """Which survey a photo belongs to, from the survey service's two callables (the hub
    wires them: this package never imports the service)."""

    def __init__(self, active_surveys: ActiveSurveys, find_survey: FindSurvey) -> None:
        self._active_surveys = active_surveys
        self._find_survey = find_survey

    async def __call__(
        self, vehicle_id: str, meta: PhotoMeta, now: float | None = None
    ) -> SurveyRun | None:
        """The survey named in the metadata, else the one the vehicle was flying when the
        photo was taken, else the one it is flying as the photo arrives. The photo's time
        is the flight controller's clock, which a simulator sped up runs ahead of the hub's
        (and a board without GPS time has wrong); the arrival covers those, the photo's own
        time the photos that arrive late, after an outage."""
        if meta.survey_id is not None:
            try:
                return await self._find_survey(meta.survey_id)
            except NotFound:
                raise Refused(Refusal.UNKNOWN_SURVEY, f"no survey {meta.survey_id}") from None
        runs = [run for run in self._active_surveys() if run.drone(vehicle_id) is not None]
        for instant in (meta.pose.time, time.time() if now is None else now):
            for run in runs:
                drone = run.drone(vehicle_id)
                assert drone is not None
                if run.started is None or instant < run.started - CLOCK_SLACK_S:
                    continue
                if drone.finished is None or instant <= drone.finished + CLOCK_SLACK_S:
                    return run
        return None
