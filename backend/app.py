"""The hub's FastAPI app factory."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator
from types import ModuleType

from fastapi import FastAPI, Request
from fastapi.middleware.cors import CORSMiddleware
from fastapi.responses import HTMLResponse, JSONResponse
from fastapi.staticfiles import StaticFiles
from sqlalchemy.exc import OperationalError

from backend.api import (
    admin,
    auth,
    fleet_commands,
    logs,
    missions,
    params,
    safety,
    system,
    vehicles,
    websockets,
)
from backend.api.docs import install_docs
from backend.api.hardening import SecurityMiddleware, content_security_policy
from backend.api.responses import document_errors
from backend.api.routing import DashboardMount, install_method_not_allowed
from backend.api.slow_clients import SlowBodyTimeout
from backend.errors import (
    GcsError,
    InvalidRequest,
    RateLimited,
    SafetyViolation,
    Unauthenticated,
)
from backend.hub import Hub
from backend.log_escaping import escape_control_characters_in_logs
from backend.settings import HubSettings

log = logging.getLogger(__name__)

API_PREFIX = "/api/v1"

_DASHBOARD_MISSING = """<!doctype html><title>Fleet GCS</title>
<h1>The dashboard is not built</h1>
<p>Run <code>npm ci &amp;&amp; npm run build</code> in <code>frontend/</code>
(or <code>make demo</code>), then reload. The API is up: see <a href="/docs">/docs</a>.</p>"""


def create_app(settings: HubSettings | None = None) -> FastAPI:
    settings = settings or HubSettings()  # fields come from the environment

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        # By now the server has configured logging (its handlers and ours).
        escape_control_characters_in_logs()
        hub = await Hub.start(settings)
        app.state.hub = hub
        runner = asyncio.create_task(hub.run(), name="hub")
        try:
            yield
        finally:
            runner.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await runner

    app = FastAPI(
        title="Fleet GCS hub",
        version="0.1.0",
        description="Live fleet state, commands and telemetry history for drone fleets.",
        lifespan=lifespan,
        docs_url=None,  # install_docs serves /docs and /redoc without a CDN
        redoc_url=None,
    )
    modules: tuple[ModuleType, ...] = (system, auth, vehicles, params, missions, fleet_commands)
    modules += (safety, *logs.ROUTE_MODULES, admin)
    routers = [module.router for module in modules]
    document_errors(app, routers)
    for router in routers:
        app.include_router(router, prefix=API_PREFIX)
    app.include_router(websockets.router)
    install_method_not_allowed(app, routers, API_PREFIX)
    install_docs(app, content_security_policy(settings.basemap_url))
    app.add_exception_handler(GcsError, _gcs_error_response)  # type: ignore[arg-type]
    app.add_exception_handler(OperationalError, _database_unavailable)  # type: ignore[arg-type]
    if settings.cors_origins:
        app.add_middleware(
            CORSMiddleware,
            allow_origins=settings.cors_origins,
            allow_credentials=True,
            allow_methods=["GET", "POST", "PUT", "PATCH", "DELETE"],
            allow_headers=["Authorization", "Content-Type"],
        )
    app.add_middleware(
        SecurityMiddleware,
        max_body_bytes=settings.max_body_bytes,
        csp=content_security_policy(settings.basemap_url),
        hsts=settings.environment == "production",
        large_bodies={r"^/api/v1/vehicles/[^/]+/tlogs$": settings.max_tlog_bytes},
    )
    app.add_middleware(
        SlowBodyTimeout, grace_s=settings.body_timeout_s, min_rate_bps=settings.body_min_rate_bps
    )
    _mount_dashboard(app, settings)
    return app


async def _gcs_error_response(request: Request, error: GcsError) -> JSONResponse:
    if isinstance(error, InvalidRequest):
        # The same shape as FastAPI's own 422s, so clients handle one format.
        detail = [
            {"loc": [error.location, error.field], "msg": error.message, "type": "value_error"}
        ]
        return JSONResponse({"detail": detail}, status_code=error.status_code)
    headers: dict[str, str] = {}
    body: dict[str, object] = {"detail": error.message}
    if isinstance(error, Unauthenticated):
        headers["WWW-Authenticate"] = "Bearer"
    elif isinstance(error, RateLimited):
        headers["Retry-After"] = str(max(1, round(error.retry_after_s)))
    elif isinstance(error, SafetyViolation):
        body["violations"] = error.violations
    return JSONResponse(body, status_code=error.status_code, headers=headers)


async def _database_unavailable(request: Request, error: OperationalError) -> JSONResponse:
    log.warning(
        "database unavailable during %s %s: %s", request.method, request.url.path, error.orig
    )
    return JSONResponse(
        {"detail": "the database is unavailable; try again shortly"},
        status_code=503,
        headers={"Retry-After": "5"},
    )


def _mount_dashboard(app: FastAPI, settings: HubSettings) -> None:
    if (settings.frontend_dir / "index.html").is_file():
        files = StaticFiles(directory=settings.frontend_dir, html=True)
        app.router.routes.append(DashboardMount(files, API_PREFIX))
        return
    log.warning("dashboard not built: %s has no index.html", settings.frontend_dir)

    @app.get("/", include_in_schema=False)
    async def dashboard_missing() -> HTMLResponse:
        return HTMLResponse(_DASHBOARD_MISSING, status_code=503)
