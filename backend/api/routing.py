"""Routing edges: the dashboard's catch-all stays off the API's paths, and a 405 names every
method its path takes."""

from __future__ import annotations

from collections.abc import Iterable

from fastapi import APIRouter, FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.responses import JSONResponse, Response
from fastapi.routing import APIRoute
from starlette.exceptions import HTTPException
from starlette.routing import Match, Mount, compile_path
from starlette.types import Scope


class DashboardMount(Mount):
    """The dashboard's files at ``/``, except under the API's prefix.

    A mount at ``/`` matches every path fully, so it used to answer before an API route
    that matched the path but not the method: a DELETE-only route got the static files'
    405 with ``Allow: GET, HEAD``, and a GET on a POST-only route an HTML 404.
    """

    def __init__(self, app: object, api_prefix: str) -> None:
        super().__init__("/", app=app, name="dashboard")  # type: ignore[arg-type]
        self.api_prefix = api_prefix.rstrip("/")

    def matches(self, scope: Scope) -> tuple[Match, Scope]:
        path: str = scope.get("path", "")
        if path == self.api_prefix or path.startswith(self.api_prefix + "/"):
            return Match.NONE, {}
        return super().matches(scope)


def install_method_not_allowed(app: FastAPI, routers: Iterable[APIRouter], prefix: str) -> None:
    """Answer a 405 with every method the path takes. Starlette names only the methods of
    the first route that matched the path, and a path often has one route per method."""
    table = [
        (compile_path(prefix + route.path)[0], route.path.count("{"), route.methods or set())
        for router in routers
        for route in router.routes
        if isinstance(route, APIRoute)
    ]

    def allowed(path: str) -> list[str]:
        # The most literal templates that match, as the OpenAPI document's path items
        # are: /surveys/preview (POST) also matches /surveys/{survey_id} (GET), which
        # does not make GET a method of /surveys/preview.
        matching = [(params, methods) for pattern, params, methods in table if pattern.match(path)]
        fewest = min((params for params, _ in matching), default=0)
        return sorted({m for params, methods in matching if params == fewest for m in methods})

    async def answer(request: Request, error: HTTPException) -> Response:
        if error.status_code != 405:
            return await http_exception_handler(request, error)
        methods = allowed(request.url.path)
        allow = ", ".join(methods) or (error.headers or {}).get("Allow", "")
        return JSONResponse(
            {"detail": f"{request.method} is not allowed here; allowed: {allow}"},
            status_code=405,
            headers={"Allow": allow},
        )

    app.add_exception_handler(HTTPException, answer)  # type: ignore[arg-type]
