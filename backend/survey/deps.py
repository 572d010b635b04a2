"""The survey's typed FastAPI dependency: its routes take the survey service, not the hub.

The app puts the service on its state when the hub starts (``app.py``); a route declares
``surveys: SurveysDep`` and is handed it.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends
from starlette.datastructures import State
from starlette.requests import HTTPConnection

from backend.survey.service import SurveyService

STATE_KEY = "surveys"


def provide(state: State, service: SurveyService) -> None:
    """Make the service the one the routes are handed (the app's lifespan calls this)."""
    setattr(state, STATE_KEY, service)


def get_surveys(connection: HTTPConnection) -> SurveyService:
    service: SurveyService = getattr(connection.app.state, STATE_KEY)
    return service


SurveysDep = Annotated[SurveyService, Depends(get_surveys)]
