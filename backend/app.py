"""The hub's FastAPI app factory."""

from __future__ import annotations

import asyncio
import contextlib
import html
import logging
from collections.abc import AsyncIterator
from pathlib import Path
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
    metrics,
    missions,
    params,
    system,
    tiles,
    vehicles,
    viz,
    viz_viewers,
    websockets,
)
from backend.api.auth import API_TOKEN_DAYS
from backend.api.docs import install_docs
from backend.api.early_refusal import EarlyRefusal, early_checks
from backend.api.hardening import SecurityMiddleware, content_security_policy
from backend.api.responses import document_errors
from backend.api.routing import DashboardMount, install_method_not_allowed
from backend.api.slow_clients import SlowBodyTimeout
from backend.auth.rate_limit import whole_seconds
from backend.errors import (
    GcsError,
    InvalidRequest,
    RateLimited,
    SafetyViolation,
    Unauthenticated,
)
from backend.formation import routes as formations
from backend.formation import wiring as formation_wiring
from backend.hub.start import start_hub
from backend.hub.work import run_hub
from backend.imagery.mosaic import deps as mosaic_deps
from backend.imagery.mosaic import routes as mosaics
from backend.imagery.photos import deps as photo_deps
from backend.imagery.photos import routes as photos
from backend.observability.logs import use_json_logs
from backend.safety import routes as safety
from backend.scans import deps as scan_deps
from backend.scans import routes as scans
from backend.scans.scene_layer import scan_scene_layers
from backend.settings import REPO_ROOT, HubSettings
from backend.survey import deps as survey_deps
from backend.survey import routes as surveys
from common.log_escaping import escape_control_characters_in_logs
from protocol.messages import AGENT_WS_PATH, CLIENT_WS_PATH

log = logging.getLogger(__name__)

API_PREFIX = "/api/v1"
# The API document's description: where a new client starts, and what /docs cannot show
# (OpenAPI has no WebSockets). Markdown, as Swagger UI and ReDoc render it.
API_DESCRIPTION = f"""Live fleet state, commands and telemetry history for drone fleets.

**Authenticating.** `POST {API_PREFIX}/auth/token` takes a form (`username`, `password`)
and answers a bearer token; send it as `Authorization: Bearer <token>` on every request.
`POST {API_PREFIX}/auth/api-tokens` makes one for an integration, limited to scopes (the
OAuth2 scheme lists them; each operation names the one it needs), which expires after
{API_TOKEN_DAYS} days unless `expires_in_days` asks for 1 to 3,650 (or null: never).

**WebSockets**, which this document cannot describe:

- `{CLIENT_WS_PATH}`, the live feed for dashboards and integrations: the same bearer
  header on the upgrade request; the fleet, then each vehicle as it changes, and events.
- `{AGENT_WS_PATH}`, the link of the vehicle agents (an agent token).

Every message, field and close code of both is in the repository's `docs/websockets.md`,
written from the wire protocol (`protocol/messages/`; `python -m protocol.messages`
prints its JSON Schema).

**From Python**, the client package `gcs_client` (its own wheel, built from the
repository's `client/`) does all of this typed, sync or async, with the live feed as an
async iterator that reconnects and token renewal built in: see the repository's
`docs/client.md`.
"""

_DASHBOARD_MISSING = """<!doctype html><title>Fleet GCS</title>
<h1>The dashboard is not built</h1>
<p>{problem}</p>
<p>In a checkout, run <code>npm ci &amp;&amp; npm run build</code> in <code>frontend/</code>
(or <code>make demo</code>); a hub installed with pip has no checkout: build the dashboard
from the source and set <code>GCS_FRONTEND_DIR</code> to its <code>frontend/dist</code>.
Then restart the hub. The API is up: see <a href="/docs">/docs</a>.</p>"""


def create_app(settings: HubSettings | None = None) -> FastAPI:
    settings = settings or HubSettings()  # fields come from the environment

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        # By now the server has configured logging (its handlers and ours).
        escape_control_characters_in_logs()
        if settings.log_format == "json":
            use_json_logs()
        hub = await start_hub(settings)
        app.state.hub = hub
        # The features, each on the started hub before it runs (their routes read them).
        app.state.formation = await formation_wiring.attach(hub)
        survey_deps.provide(app.state, hub.surveys)  # the survey's routes take its service
        photo_deps.provide(app.state, hub.photos)  # the imagery's routes too
        mosaic_deps.provide(app.state, hub.mosaic)
        scan_deps.provide(
            app.state,
            scan_deps.ScanRouteServices(hub.scans, hub.refresh_obstacles),
        )
        hub.scene_layers.extend(scan_scene_layers(hub.scans, hub.bus))
        runner = asyncio.create_task(run_hub(hub), name="hub")
        try:
            yield
        finally:
            runner.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await runner

    app = FastAPI(
        title="Fleet GCS hub",
        version="0.1.0",
        description=API_DESCRIPTION,
        lifespan=lifespan,
        docs_url=None,  # install_docs serves /docs and /redoc without a CDN
        redoc_url=None,
    )
    modules: tuple[ModuleType, ...] = (system, auth, vehicles, params, missions, fleet_commands)
    modules += (safety, surveys, photos, formations, scans, *logs.ROUTE_MODULES, admin, tiles)
    modules += (mosaics, viz_viewers)
    routers = [module.router for module in modules]
    document_errors(app, routers)
    for router in routers:
        app.include_router(router, prefix=API_PREFIX)
    app.include_router(websockets.router)
    app.include_router(metrics.router)  # /metrics, where Prometheus looks by default
    app.include_router(viz.router)
    app.include_router(tiles.tile_router)  # /tiles/<name>/{z}/{x}/{y}, beside the API
    install_method_not_allowed(app, routers, API_PREFIX)
    install_docs(app, content_security_policy(*settings.online_tile_urls))
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
    # Inside the security headers: a refusal made early carries them too.
    app.add_middleware(EarlyRefusal, checks=early_checks(API_PREFIX))
    app.add_middleware(
        SecurityMiddleware,
        max_body_bytes=settings.max_body_bytes,
        csp=content_security_policy(*settings.online_tile_urls),
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
        headers["Retry-After"] = str(whole_seconds(error.retry_after_s))
    elif isinstance(error, SafetyViolation):
        body["violations"] = error.violations
    return JSONResponse(body, status_code=error.status_code, headers=headers)


async def _database_unavailable(request: Request, error: OperationalError) -> JSONResponse:
    # A WebSocket's scope has no method: say so rather than fail in the handler itself.
    method = request.scope.get("method", "WEBSOCKET")
    log.warning("database unavailable during %s %s: %s", method, request.url.path, error.orig)
    return JSONResponse(
        {"detail": "the database is unavailable; try again shortly"},
        status_code=503,
        headers={"Retry-After": "5"},
    )


def dashboard_dir(configured: Path | None, package_root: Path) -> tuple[Path | None, str]:
    """Where the built dashboard is, or None and why not (a sentence naming the setting).

    ``GCS_FRONTEND_DIR`` when set; else ``frontend/dist`` of the checkout the hub runs
    from. An installed hub's package root is site-packages, which holds no dashboard: it
    is not searched there, and the answer says to set the variable."""
    if configured is not None:
        if (configured / "index.html").is_file():
            return configured, ""
        return None, f"GCS_FRONTEND_DIR={configured} has no index.html"
    if not (package_root / "pyproject.toml").is_file():
        return None, "GCS_FRONTEND_DIR is not set, and this hub does not run from a checkout"
    built = package_root / "frontend" / "dist"
    if (built / "index.html").is_file():
        return built, ""
    return None, f"{built} has no index.html (GCS_FRONTEND_DIR is not set)"


def _mount_dashboard(app: FastAPI, settings: HubSettings) -> None:
    directory, problem = dashboard_dir(settings.frontend_dir, REPO_ROOT)
    if directory is not None:
        files = StaticFiles(directory=directory, html=True)
        app.router.routes.append(DashboardMount(files, API_PREFIX))
        return
    log.warning("dashboard not served: %s", problem)
    page = _DASHBOARD_MISSING.format(problem=html.escape(problem[0].upper() + problem[1:] + "."))

    @app.get("/", include_in_schema=False)
    async def dashboard_missing() -> HTMLResponse:
        return HTMLResponse(page, status_code=503)
