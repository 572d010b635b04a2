"""The API's reference pages (/docs: Swagger UI, /redoc: ReDoc), served from the hub itself.

FastAPI's own pages load their scripts from a CDN, which the hub's CSP (``script-src
'self'``) forbids and a field network often cannot reach, and they start Swagger UI with
an inline script, which the CSP forbids too. Here the scripts come from the
``fastapi-offline`` package's copy of swagger-ui-dist and ReDoc, and Swagger UI starts
from a script file of our own, which turns off its online validator's badge (an image
from validator.swagger.io). ReDoc's sidebar draws its vendor's logo from cdn.redoc.ly
whatever its options say: the bundle is served with that address pointing at a logo
of ours.
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
  validatorUrl: null,
});
"""

_REDOC_PAGE = f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>{{title}}: API</title>
<link rel="icon" href="{ASSETS}/favicon.png"></head>
<body><redoc spec-url="/openapi.json"></redoc>
<script src="{ASSETS}/redoc.standalone.js"></script></body></html>
"""


REDOC_VENDOR_LOGO = "https://cdn.redoc.ly/redoc/logo-mini.svg"
# A page with a folded corner, in ReDoc's sidebar grey, where its vendor's logo was.
_REDOC_LOGO = """<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 16 16" width="16" height="16">
<path d="M3 1h7l3 3v11H3z" fill="none" stroke="#7a7a7a" stroke-width="1.2"/>
<path d="M10 1v3h3M5 7h6M5 10h6M5 13h4" fill="none" stroke="#7a7a7a" stroke-width="1.2"/>
</svg>
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

    bundle = (asset_dir() / "redoc.standalone.js").read_text(encoding="utf-8")
    bundle = bundle.replace(REDOC_VENDOR_LOGO, f"{ASSETS}/redoc-logo.svg")

    # Before the mount, so this route answers for the bundle rather than the file.
    @app.get(f"{ASSETS}/redoc.standalone.js", include_in_schema=False)
    async def redoc_bundle() -> Response:
        return Response(bundle, media_type="text/javascript")

    @app.get(f"{ASSETS}/redoc-logo.svg", include_in_schema=False)
    async def redoc_logo() -> Response:
        return Response(_REDOC_LOGO, media_type="image/svg+xml")

    app.mount(ASSETS, StaticFiles(directory=asset_dir()), name="docs-assets")
