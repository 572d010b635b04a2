"""docs/websockets.md is written from protocol/messages.py (scripts/gen_websocket_docs.py):
the page must say what the protocol module says, message for message and code for code."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

from protocol.messages import CloseCode, hub_to_agent, hub_to_client

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "gen_websocket_docs.py"
PAGE = ROOT / "docs" / "websockets.md"


def generator() -> ModuleType:
    spec = importlib.util.spec_from_file_location("gen_websocket_docs", SCRIPT)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_socket_page_matches_the_protocol_module() -> None:
    assert PAGE.read_text() == generator().render(), (
        "docs/websockets.md is stale: run .venv/bin/python scripts/gen_websocket_docs.py"
    )


def test_the_page_names_every_message_and_close_code() -> None:
    page = PAGE.read_text()
    for code in CloseCode:
        assert f"| {code:d} | `{code.name}` |" in page
    for adapter in (hub_to_agent, hub_to_client):
        for tag in adapter.json_schema()["discriminator"]["mapping"]:
            assert f"#### `{tag}` (" in page
    assert "#### `ping` (client → hub)" in page
    assert "Authorization: Bearer <token>" in page
