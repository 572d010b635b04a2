"""An API token expires (90 days unless its creator asks otherwise): every place that
tells an integrator about API tokens says so, and none calls them long-lived."""

from __future__ import annotations

import json
from pathlib import Path

from backend.api.auth import API_TOKEN_DAYS, ApiTokenRequest
from backend.openapi_document import openapi_document
from tests.support.docs import pages

ROOT = Path(__file__).resolve().parents[3]


def test_the_default_lifetime_is_the_request_s_default() -> None:
    assert ApiTokenRequest(name="x").expires_in_days == API_TOKEN_DAYS


def test_the_api_document_says_when_an_api_token_expires() -> None:
    document = openapi_document()
    description = " ".join(document["info"]["description"].split())
    assert f"expires after {API_TOKEN_DAYS} days" in description
    create = document["paths"]["/api/v1/auth/api-tokens"]["post"]
    assert f"({API_TOKEN_DAYS} by default; 1 to 3,650)" in create["description"]
    field = document["components"]["schemas"]["ApiTokenRequest"]["properties"]
    assert field["expires_in_days"]["default"] == API_TOKEN_DAYS
    assert f"({API_TOKEN_DAYS} if not given)" in field["expires_in_days"]["description"]
    assert "long-lived" not in json.dumps(document).lower()


def test_the_readme_and_the_socket_page_say_it_too() -> None:
    for page in pages():
        assert "long-lived" not in page.read_text().lower(), page
    for page in ("docs/integrator.md", "docs/websockets.md"):
        text = " ".join((ROOT / page).read_text().split())
        assert f"{API_TOKEN_DAYS} days unless" in text, page
