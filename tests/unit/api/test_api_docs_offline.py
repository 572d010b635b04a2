"""/docs and /redoc ask nothing of another host: the files they load, as the hub serves
them (the pages themselves render in tests/browser/test_api_docs.py)."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from fastapi import FastAPI

from backend.api.docs import ASSETS, REDOC_VENDOR_LOGO, asset_dir, install_docs
from tests.conftest import hub_settings
from tests.support.hub_server import running_hub


@pytest.fixture
def client(tmp_path: Path) -> Iterator[httpx.Client]:
    """The docs pages alone, served by uvicorn on a real socket."""
    app = FastAPI(docs_url=None, redoc_url=None)
    install_docs(app, "default-src 'self'")
    with running_hub(hub_settings(tmp_path), app=app) as base, httpx.Client(base_url=base) as c:
        yield c


def test_redoc_draws_its_sidebar_logo_from_the_hub(client: httpx.Client) -> None:
    # The package's bundle has the vendor's address (else this fix is no longer needed).
    assert REDOC_VENDOR_LOGO in (asset_dir() / "redoc.standalone.js").read_text()
    bundle = client.get(f"{ASSETS}/redoc.standalone.js")
    assert bundle.status_code == 200
    assert bundle.headers["content-type"].startswith("text/javascript")
    assert "cdn.redoc.ly" not in bundle.text
    images = set(re.findall(r'src:"([^"]+)"', bundle.text))
    assert images == {f"{ASSETS}/redoc-logo.svg"}
    logo = client.get(f"{ASSETS}/redoc-logo.svg")
    assert logo.status_code == 200
    assert logo.headers["content-type"].startswith("image/svg+xml")
    assert logo.text.startswith("<svg")


def test_swagger_ui_shows_no_online_validator_badge(client: httpx.Client) -> None:
    """Swagger UI's badge is an image from validator.swagger.io, drawn for any hub not on
    localhost: turned off."""
    init = client.get(f"{ASSETS}/swagger-init.js")
    assert init.status_code == 200
    assert "validatorUrl: null," in init.text
    page = client.get("/docs").text
    assert re.findall(r'(?:src|href)="([^"]+)"', page) == [
        f"{ASSETS}/favicon.png",
        f"{ASSETS}/swagger-ui.css",
        f"{ASSETS}/swagger-ui-bundle.js",
        f"{ASSETS}/swagger-init.js",
    ]
