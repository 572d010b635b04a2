"""docs/websockets.md is written from protocol/messages/ (scripts/gen_websocket_docs.py):
the page must say what the protocol module says, message for message and code for code."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path
from types import ModuleType

from backend.openapi_document import openapi_document
from protocol.messages import (
    AGENT_WS_PATH,
    CLIENT_WS_PATH,
    CloseCode,
    client_to_hub,
    hub_to_agent,
    hub_to_client,
)

ROOT = Path(__file__).resolve().parents[3]
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


def test_every_anchor_is_unique_and_every_link_on_the_page_leads_to_one() -> None:
    page = PAGE.read_text()
    anchors = re.findall(r'<a id="([^"]+)"></a>', page)
    assert len(anchors) == len(set(anchors)), sorted(a for a in anchors if anchors.count(a) > 1)
    # A heading is a target too, by the slug GitHub gives it ("### VehicleState").
    headings = re.findall(r"^#+ (.+)$", page, flags=re.MULTILINE)
    slugs = {re.sub(r"[^\w\- ]", "", heading.lower()).replace(" ", "-") for heading in headings}
    links = set(re.findall(r"\]\(#([^)]+)\)", page))
    assert links - set(anchors) - slugs == set()


def test_the_live_feeds_conversation_names_every_message_a_client_may_send() -> None:
    conversation = PAGE.read_text().split("### The conversation", 1)[1].split("### Messages")[0]
    steps = re.findall(r"^(\d+)\. ", conversation, flags=re.MULTILINE)
    assert steps == [str(n) for n in range(1, len(steps) + 1)], steps
    for tag in client_to_hub.json_schema()["discriminator"]["mapping"]:
        assert f"[`{tag}`](#" in conversation, tag


def test_the_openapi_document_sends_a_reader_to_the_socket_page() -> None:
    """OpenAPI cannot describe a WebSocket: its description (the top of /docs) names both
    sockets, how to authenticate on them, and the page that has the rest."""
    description = openapi_document()["info"]["description"]
    assert f"`{CLIENT_WS_PATH}`" in description
    assert f"`{AGENT_WS_PATH}`" in description
    assert "Authorization: Bearer <token>" in description
    assert "docs/websockets.md" in description
