"""Print every vehicle update from the hub's live feed.

python examples/02_watch_the_fleet.py ws://127.0.0.1:8000/api/v1/ws
"""

import json
import sys

from websockets.sync.client import connect

url = sys.argv[1] if len(sys.argv) > 1 else "ws://127.0.0.1:8000/api/v1/ws"
with connect(url) as feed:
    for frame in feed:
        message = json.loads(frame)
        if message["type"] == "fleet":
            print("fleet:", [vehicle["id"] for vehicle in message["vehicles"]])
        elif message["type"] == "vehicle":
            vehicle = message["vehicle"]
            state = vehicle["state"] or {}
            print(
                f"{vehicle['id']:12} {state.get('mode')} armed={state.get('armed')} "
                f"alt={state.get('alt_rel')}"
            )
