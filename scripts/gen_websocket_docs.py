"""Write docs/websockets.md from the wire protocol (protocol/messages/) and the hub's
settings: the two sockets, how each authenticates, every message with its fields, the
keep-alive and the close codes.

    .venv/bin/python scripts/gen_websocket_docs.py          # rewrite the page
    .venv/bin/python scripts/gen_websocket_docs.py --check  # exit 1 if it is stale

tests/unit/protocol/test_websocket_docs.py fails when the page and the protocol module differ.
The prose is here; every name, number, field and close code comes from the code.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from backend.api.auth import API_TOKEN_DAYS  # noqa: E402
from backend.auth.credentials import SESSION_COOKIE  # noqa: E402
from backend.auth.policy import AGENT_MESSAGE_PERMISSIONS, CLIENT_MESSAGE_PERMISSIONS  # noqa: E402
from backend.realtime.agent_gateway.handshake import HELLO_TIMEOUT_S  # noqa: E402
from backend.realtime.live_events import DEFAULT_QUEUE_EVENTS  # noqa: E402
from backend.settings import HubSettings  # noqa: E402
from protocol import messages  # noqa: E402
from protocol.messages import CloseCode  # noqa: E402
from scripts.websocket_docs.close_codes import close_code_meanings  # noqa: E402
from scripts.websocket_docs.schema_markdown import (  # noqa: E402
    all_definitions,
    anchor,
    cell,
    description_of,
    field_table,
    message_section,
    type_section,
    union_members,
)

PAGE = ROOT / "docs" / "websockets.md"
# uvicorn's defaults, which `gcs hub` keeps: a WebSocket ping every 20 s, and a peer
# that has not answered one within 20 s is gone.
HUB_PING_INTERVAL_S = 20
HUB_PING_TIMEOUT_S = 20


def render() -> str:
    definitions = all_definitions()
    meanings = close_code_meanings()
    defaults = HubSettings.model_fields
    max_bad_frames = defaults["max_bad_frames"].default
    ui_interval_s = defaults["ui_update_interval_s"].default
    vehicle_interval_s = defaults["ui_vehicle_interval_s"].default
    batch_interval_s = defaults["ui_batch_interval_s"].default
    slow_client_s = defaults["slow_client_timeout_s"].default
    client_to_hub = union_members(messages.ClientToHub)
    hub_to_client = union_members(messages.HubToClient)
    agent_to_hub = union_members(messages.AgentToHub)
    hub_to_agent = union_members(messages.HubToAgent)
    commands = union_members(messages.Command)
    shown = set(client_to_hub + hub_to_client + agent_to_hub + hub_to_agent + commands)
    shared = sorted(name for name in definitions if name not in shown)
    client_permissions = ", ".join(
        f"`{kind}` needs `{permission}`" for kind, permission in CLIENT_MESSAGE_PERMISSIONS.items()
    )
    agent_kinds = ", ".join(f"`{kind}`" for kind in AGENT_MESSAGE_PERMISSIONS)
    anchored: set[str] = set()

    out = [
        "# The WebSockets: the live feed and the agent link",
        "",
        "<!-- Written by scripts/gen_websocket_docs.py from protocol/messages/; do not edit.",
        "     After changing the protocol, run: .venv/bin/python scripts/gen_websocket_docs.py -->",
        "",
        "The hub has two WebSockets besides its REST API (which `/docs` describes):",
        "",
        f"- `{messages.CLIENT_WS_PATH}`, the **live feed** for dashboards and integrations: the "
        "fleet, then each vehicle as it changes.",
        f"- `{messages.AGENT_WS_PATH}`, the **agent link**, for the vehicle agents only: "
        "telemetry and events up, commands down.",
        "",
        # A literal: backend.api.viz would import viser, and its socket is not ours.
        "(The 3D view's page under `/viz/` has a socket too; it carries viser's own wire "
        "format to that page and is not an API.)",
        "",
        "On both, every frame is one JSON object as text, and its `type` names the message. "
        f"A frame is at most {messages.MAX_FRAME_BYTES:,} bytes (the hub closes with "
        f"{CloseCode.MESSAGE_TOO_BIG:d} beyond). A frame the hub cannot use is answered with an "
        f"[`error`](#errorreply) and the connection stays open; after {max_bad_frames} of them "
        f"(`GCS_MAX_BAD_FRAMES`) the hub closes it with {CloseCode.POLICY_VIOLATION:d}. "
        "The message schemas are also published as JSON Schema: "
        "`python -m protocol.messages`.",
        "",
        "## The live feed",
        "",
        "### Authenticating",
        "",
        "The feed takes the same credentials as the REST API, on the upgrade request, and "
        "needs the `read` permission (every role has it):",
        "",
        "- **A script** sends `Authorization: Bearer <token>`. The token is an access token "
        "from `POST /api/v1/auth/token` (a form with `username` and `password`; it expires) "
        "or an API token from `POST /api/v1/auth/api-tokens` (scoped, revocable; it expires after "
        f"{API_TOKEN_DAYS} days unless its `expires_in_days` says otherwise). "
        "With Python's `websockets`: "
        "`connect(url, additional_headers={'Authorization': f'Bearer {token}'})`.",
        "- **A browser** cannot set headers on a WebSocket: it logs in with "
        f"`POST /api/v1/auth/login`, and sends the HTTP-only `{SESSION_COOKIE}` cookie that "
        "sets. The page's `Origin` must be the hub's own (same scheme and host) or one of "
        f"`GCS_CORS_ORIGINS`, else the hub closes with {CloseCode.FORBIDDEN:d}.",
        "- A token in the URL is not accepted: URLs end up in logs.",
        "",
        f"Without a credential the hub closes with {CloseCode.UNAUTHORIZED:d}, and the reason says "
        "what to send; with an invalid, expired or revoked one, also "
        f"{CloseCode.UNAUTHORIZED:d}. An open feed lasts as long as its credential: the hub "
        f"closes it with {CloseCode.UNAUTHORIZED:d} when the token expires, is revoked, or its "
        "user logs out or is disabled. Log in again before reconnecting; retrying with the "
        "same token cannot succeed.",
        "",
        "### The conversation",
        "",
        "1. The hub sends [`fleet`](#fleetsnapshot): every vehicle it knows, connected or not.",
        "2. Then [`vehicles`](#vehiclebatch): the vehicles that changed, batched, each at its "
        f"newest state: at most one update per vehicle every {vehicle_interval_s:g} s "
        f"(`GCS_UI_VEHICLE_INTERVAL_S`) and one batch every {batch_interval_s:g} s "
        "(`GCS_UI_BATCH_INTERVAL_S`), a change going out at once when neither holds it back. "
        "An update not yet sent is replaced, never queued. A client that reads nothing for "
        f"{slow_client_s:g} s (`GCS_SLOW_CLIENT_TIMEOUT_S`) is closed with "
        f"{CloseCode.TOO_SLOW:d}.",
        "3. Meanwhile [`events`](#eventbatch): what the vehicles and the hub report from the "
        "moment of connecting (STATUSTEXTs with their severity, mode changes, failsafes, "
        "links going up and down, each command's result), in batches at most every "
        f"{ui_interval_s:g} s, identical ones folded into one with a `repeat` count. Events are "
        "not replaced by newer ones: each client's queue holds "
        f"{DEFAULT_QUEUE_EVENTS} and, when full, drops the least severe first, counting them "
        "in `dropped`. Older events are in the flight log (`GET /api/v1/events`).",
        "4. The client may send [`ping`](#ping) at any time; the hub answers "
        "[`pong`](#pong) with the same `nonce`.",
        "5. Flying by hand: [`control`](#controlrequest) asks for a vehicle's manual-control "
        "lease (or gives it back); every feed then gets [`lease`](#leasestate), naming who "
        "holds it. A refusal goes to the asking client as [`lease_refused`](#leaserefusal) "
        "with the reason (and, where the vehicle's setup is the reason, the parameter change "
        "that would lift it), and to every feed as a `manual` event. The holder streams "
        "[`manual`](#manualinput) frames; one without the lease is "
        "answered with `forbidden` too.",
        "6. LIDAR scans: after [`subscribe_scans`](#subscribescans) for a vehicle (answered "
        "with [`scan_subscriptions`](#scansubscriptions)) and until "
        "[`unsubscribe_scans`](#unsubscribescans), the hub sends that vehicle's scans "
        "as **binary** frames: `GSCV`, the vehicle id's length (one byte) and the id, then "
        "the agent's scan frame, laid out in `protocol/scans.py` (uint16 millimetre ranges, "
        "the poses at the turn's start and end; 1,580 bytes for 720 beams). Only the newest "
        "scan of each subscribed vehicle is kept for a feed: a client that reads slowly "
        "gets fewer scans, never a queue. A feed that subscribed to nothing gets none.",
        "7. The site map: after [`subscribe_map`](#subscribemap) with its `layers` (answered "
        "with [`map_subscriptions`](#mapsubscriptions)) and until "
        "[`unsubscribe_map`](#unsubscribemap), the hub sends each layer as it is at once, "
        "then as it changes: [`point_map`](#pointmapupdate), the newest voxels of the point "
        "map, at most every 2 s, and [`obstacles`](#obstaclesupdate), the clusters found in "
        "it, when one is found or gone. A slow reader gets the newest of each, never a queue.",
        "",
        f"A client may send these messages only, each needing a permission ({client_permissions}); "
        "anything else is answered with an [`error`](#errorreply).",
        "",
        "Commands are not sent on the feed: they go through the REST API "
        "(`POST /api/v1/vehicles/{id}/commands`, `POST /api/v1/fleet/commands`), which "
        "answers with the flight controller's verdict.",
        "",
        "### Messages",
        "",
    ]
    for name in client_to_hub:
        out += message_section(name, definitions[name], "client → hub", anchored)
    for name in hub_to_client:
        if name != "ErrorReply":
            out += message_section(name, definitions[name], "hub → client", anchored)
    out += [
        "## The agent link",
        "",
        "### Authenticating",
        "",
        "An agent sends `Authorization: Bearer <agent token>` on the upgrade request. An "
        "agent token belongs to one vehicle: an admin makes it with "
        "`POST /api/v1/vehicles/{id}/agent-tokens` (or provisions it with `GCS_AGENT_TOKENS`). "
        f"A missing, wrong or revoked token, or a user's token, is closed with "
        f"{CloseCode.UNAUTHORIZED:d}; a `hello` for another vehicle with "
        f"{CloseCode.FORBIDDEN:d}. Revoking the token closes its live connection at once "
        f"({CloseCode.UNAUTHORIZED:d}).",
        "",
        "### The conversation",
        "",
        f"1. The agent sends [`hello`](#hello) within {HELLO_TIMEOUT_S:g} s, announcing "
        f"protocol {messages.PROTOCOL_VERSION}; anything else, or another protocol version, "
        f"is closed with {CloseCode.BAD_HELLO:d}.",
        "2. The hub answers [`welcome`](#welcome).",
        "3. The agent streams [`telemetry`](#telemetry) and [`event`](#event), each numbered "
        "per kind in its stream (`seq`), [`live_state`](#livestate) while it replays a "
        "backlog, and [`scan_source_stats`](#scansourcestats) when its LIDAR parser's counts "
        "change (every 5 s at most). The hub sends [`ack`](#ack) once frames are stored "
        "(after the commit), "
        "and [`resend`](#resend) when it sees a gap; the agent replays those frames or "
        "answers [`unavailable`](#unavailable) for frames its full outbox had to drop.",
        "4. The hub sends [`command`](#commandrequest); the agent answers "
        "[`command_result`](#commandresult) with the same `request_id`.",
        "",
        f"Agent messages ({agent_kinds}) need the agent permission of the vehicle the "
        "connection is for.",
        "",
        "### Messages",
        "",
    ]
    for name in agent_to_hub:
        out += message_section(name, definitions[name], "agent → hub", anchored)
    for name in hub_to_agent:
        if name != "ErrorReply":
            out += message_section(name, definitions[name], "hub → agent", anchored)
    out += [
        "## Errors on either socket",
        "",
        *message_section("ErrorReply", definitions["ErrorReply"], "hub → agent or client"),
        "## Keep-alive",
        "",
        f"The hub sends a WebSocket ping every {HUB_PING_INTERVAL_S} s and drops a peer "
        f"that has not answered within {HUB_PING_TIMEOUT_S} s (close 1011). WebSocket "
        "libraries and browsers answer pings by themselves. The feed's [`ping`](#ping) "
        "message is for a client that wants to see the hub answer (a round trip through "
        "its handler).",
        "",
        "## Close codes",
        "",
        "| code | name | meaning |",
        "| --- | --- | --- |",
    ]
    out += [f"| {code:d} | `{code.name}` | {cell(meanings[code])} |" for code in CloseCode]
    out += [
        "",
        "The close frame's reason says more (at most 123 bytes).",
        "",
        "## Types used in messages",
        "",
    ]
    for name in shared:
        out += type_section(name, definitions[name])
    out += [
        '<a id="commands"></a>',
        "### Commands",
        "",
        "A command's `name` picks it; the same bodies are what "
        "`POST /api/v1/vehicles/{id}/commands` takes.",
        "",
    ]
    for name in commands:
        schema = definitions[name]
        tag = schema["properties"]["name"]["const"]
        out += [
            f'<a id="{anchor(name)}"></a>',
            f"#### `{tag}`",
            "",
            *description_of(schema),
            *field_table(schema),
            "",
        ]
    return "\n".join(out).rstrip() + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if the page is stale")
    args = parser.parse_args()
    page = render()
    if args.check:
        if PAGE.read_text() != page:
            print(f"{PAGE} is stale: run scripts/gen_websocket_docs.py", file=sys.stderr)
            return 1
        return 0
    PAGE.write_text(page)
    print(f"wrote {PAGE.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
