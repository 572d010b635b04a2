"""Follow the hub's live feed: the fleet first, then each vehicle as it changes.

    GCS_HUB=http://127.0.0.1:8000 GCS_TOKEN=... python examples/02_watch_the_fleet.py [--updates N]

The feed is a WebSocket at /api/v1/ws that takes the same bearer token as the REST API
(docs/websockets.md lists every message and close code). It stops after N vehicle
updates, or never without --updates.
"""

import argparse
import json

from hubclient import closed_reason, feed_address, token
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--updates", type=int, help="stop after this many vehicle updates")
args = parser.parse_args()

headers = {"Authorization": f"Bearer {token()}"}
try:
    with connect(feed_address(), additional_headers=headers) as feed:
        # Any message from us is answered; a ping shows the connection is alive.
        feed.send(json.dumps({"type": "ping", "nonce": "hello"}))
        updates = 0
        for frame in feed:
            message = json.loads(frame)
            if message["type"] == "fleet":
                print("fleet:", ", ".join(vehicle["id"] for vehicle in message["vehicles"]))
            elif message["type"] == "pong":
                print("pong:", message["nonce"])
            elif message["type"] == "error":
                raise SystemExit(f"error: {message['code']}: {message['message']}")
            elif message["type"] == "vehicles":  # the vehicles that changed, batched
                for vehicle in message["vehicles"]:
                    state = vehicle["state"] or {}
                    print(
                        f"{vehicle['id']:12} {state.get('mode', '?'):10} "
                        f"armed={state.get('armed')} alt={state.get('alt_rel')} "
                        f"battery={state.get('battery_remaining')}%"
                    )
                    updates += 1
                if updates >= args.updates:
                    break
except ConnectionClosed as closed:
    raise SystemExit(f"error: the hub closed the live feed: {closed_reason(closed)}") from None
