"""The dashboard's REST types are generated from the hub's OpenAPI document and kept in step."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from backend.openapi_document import openapi_document

FRONTEND = Path(__file__).resolve().parents[3] / "frontend"
GENERATOR = FRONTEND / "scripts" / "gen-api"


@pytest.mark.skipif(
    not (GENERATOR / "node_modules" / "openapi-typescript").is_dir()
    and not (FRONTEND / "node_modules" / "openapi-typescript").is_dir(),
    reason="npm packages not installed (scripts/setup.sh installs them)",
)
def test_generated_typescript_matches_the_hubs_openapi() -> None:
    node = shutil.which("node")
    assert node, "node is required to build the dashboard"
    generated = subprocess.run(
        [node, str(GENERATOR / "gen-api.mjs")],
        input=json.dumps(openapi_document()),
        capture_output=True,
        text=True,
        cwd=FRONTEND,
        timeout=120,
        check=True,
    ).stdout
    committed = (FRONTEND / "src" / "generated" / "api.ts").read_text()
    assert generated == committed, (
        "frontend/src/generated/api.ts is stale: run `npm run gen:api` in frontend/"
    )
