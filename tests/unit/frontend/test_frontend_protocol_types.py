"""The dashboard's TypeScript types are generated from protocol/messages/ and kept in step."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from protocol.messages import json_schema

FRONTEND = Path(__file__).resolve().parents[3] / "frontend"


@pytest.mark.skipif(
    not (FRONTEND / "node_modules" / "json-schema-to-typescript").is_dir(),
    reason="npm packages not installed (scripts/setup.sh installs them)",
)
def test_generated_typescript_matches_the_python_protocol() -> None:
    node = shutil.which("node")
    assert node, "node is required to build the dashboard"
    generated = subprocess.run(
        [node, "scripts/gen-protocol.mjs"],
        input=json.dumps(json_schema()),
        capture_output=True,
        text=True,
        cwd=FRONTEND,
        timeout=60,
        check=True,
    ).stdout
    committed = (FRONTEND / "src" / "generated" / "protocol.ts").read_text()
    assert generated == committed, (
        "frontend/src/generated/protocol.ts is stale: run `npm run gen:protocol` in frontend/"
    )
