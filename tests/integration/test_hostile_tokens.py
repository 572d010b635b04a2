"""Every protected route of the OpenAPI document refuses a request with no token, a
forged one (signed with another secret), and another hub's real token, with a 401, before
any of its own logic runs (unknown ids, bodies: still a 401)."""

from __future__ import annotations

import re
from pathlib import Path

import httpx
import pytest

from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import access_token
from tests.support.hub_server import running_hub

PUBLIC = {"/api/v1/health", "/api/v1/auth/token", "/api/v1/auth/login"}


@pytest.fixture
def foreign_token(tmp_path: Path) -> str:
    """A real admin token of another hub (its own database of sessions)."""
    (tmp_path / "other").mkdir()
    with running_hub(hub_settings(tmp_path / "other")) as other:
        return access_token(other, "admin", ADMIN_PASSWORD)


def test_every_protected_route_refuses_missing_forged_and_foreign_tokens(
    hub: str, foreign_token: str
) -> None:
    document = httpx.get(f"{hub}/openapi.json").json()
    forged = foreign_token[:-8] + ("A" * 8 if not foreign_token.endswith("A" * 8) else "B" * 8)
    presented = {
        "missing": {},
        "forged": {"Authorization": f"Bearer {forged}"},
        "foreign": {"Authorization": f"Bearer {foreign_token}"},
        "garbage": {"Authorization": "Bearer not a token"},
    }
    wrong: dict[str, int] = {}
    checked = 0
    with httpx.Client(base_url=hub, timeout=10) as client:
        for path, operations in document["paths"].items():
            for method, operation in operations.items():
                if path in PUBLIC or not operation.get("security"):
                    continue
                # "1" matches every id's pattern (hex survey ids, numbers, names)
                url = re.sub(r"\{[^}]+\}", "1", path)
                for name, headers in presented.items():
                    response = client.request(method, url, headers=headers, json={})
                    checked += 1
                    if response.status_code != 401:
                        wrong[f"{method.upper()} {path} ({name})"] = response.status_code
    assert checked > 150, checked  # the routes were found
    assert not wrong, wrong
