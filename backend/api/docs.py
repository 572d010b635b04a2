"""The API's reference pages (/docs: Swagger UI, /redoc: ReDoc), served from the hub itself.

FastAPI's own pages load their scripts from a CDN, which the hub's CSP (``script-src
'self'``) forbids and a field network often cannot reach, and they start Swagger UI with
an inline script, which the CSP forbids too. Here the scripts come from the
``fastapi-offline`` package's copy of swagger-ui-dist and ReDoc, and Swagger UI starts
from a script file of our own.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from fastapi import FastAPI
from fastapi.responses import HTMLResponse, Response
from fastapi.staticfiles import StaticFiles

ASSETS = "/docs-assets"

_SWAGGER_PAGE = f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>{{title}}: API</title>
<link rel="icon" href="{ASSETS}/favicon.png">
<link rel="stylesheet" href="{ASSETS}/swagger-ui.css"></head>
<body><div id="swagger-ui"></div>
<script src="{ASSETS}/swagger-ui-bundle.js"></script>
<script src="{ASSETS}/swagger-init.js"></script></body></html>
"""

_SWAGGER_INIT = """window.ui = SwaggerUIBundle({
  url: "/openapi.json",
  dom_id: "#swagger-ui",
  deepLinking: true,
  showExtensions: true,
  presets: [SwaggerUIBundle.presets.apis, SwaggerUIBundle.SwaggerUIStandalonePreset],
  layout: "BaseLayout",
});
"""

_REDOC_PAGE = f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>{{title}}: API</title>
<link rel="icon" href="{ASSETS}/favicon.png"></head>
<body><redoc spec-url="/openapi.json"></redoc>
<script src="{ASSETS}/redoc.standalone.js"></script></body></html>
"""


def asset_dir() -> Path:
    """swagger-ui-bundle.js, swagger-ui.css, redoc.standalone.js and favicon.png."""
    return Path(str(files("fastapi_offline") / "static"))


def install_docs(app: FastAPI, csp: str) -> None:
    """Serve /docs and /redoc with local assets (create the app with docs_url=None and
    redoc_url=None so FastAPI does not add its CDN pages). ``csp`` is the hub's policy:
    the ReDoc page's own adds that it may start its search index in a worker."""
    swagger = _SWAGGER_PAGE.replace("{title}", app.title)
    redoc = _REDOC_PAGE.replace("{title}", app.title)
    redoc_csp = f"{csp}; worker-src 'self' blob:"

    @app.get("/docs", include_in_schema=False)
    async def swagger_ui() -> HTMLResponse:
        return HTMLResponse(swagger)

    @app.get("/redoc", include_in_schema=False)
    async def redoc_ui() -> HTMLResponse:
        return HTMLResponse(redoc, headers={"Content-Security-Policy": redoc_csp})

    @app.get(f"{ASSETS}/swagger-init.js", include_in_schema=False)
    async def swagger_init() -> Response:
        return Response(_SWAGGER_INIT, media_type="text/javascript")

    app.mount(ASSETS, StaticFiles(directory=asset_dir()), name="docs-assets")
