"""Follow the hub's live feed: the fleet first, then each vehicle as it changes.

    GCS_HUB=http://127.0.0.1:8000 GCS_TOKEN=... python examples/02_watch_the_fleet.py [--updates N]

The feed is a WebSocket at /api/v1/ws (docs/websockets.md lists every message and close
code); `hub.feed()` yields its messages typed, and reconnects by itself if the link drops.
It stops after N vehicle updates, or never without --updates.
"""

import argparse
import asyncio

from gcs_client import Hub, HubError
from gcs_client.models import ErrorReply, FleetSnapshot, Ping, Pong, VehicleBatch

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--updates", type=int, help="stop after this many vehicle updates")
args = parser.parse_args()


async def watch() -> None:
    async with Hub.from_env() as hub:
        feed = hub.feed()
        updates = 0
        async for message in feed:
            if isinstance(message, FleetSnapshot):
                print("fleet:", ", ".join(vehicle.id for vehicle in message.vehicles))
                # Any message from us is answered; a ping shows the hub is listening.
                await feed.send(Ping(nonce="hello"))
            elif isinstance(message, Pong):
                print("pong:", message.nonce)
            elif isinstance(message, ErrorReply):
                raise SystemExit(f"error: {message.code}: {message.message}")
            elif isinstance(message, VehicleBatch):  # the vehicles that changed, batched
                for vehicle in message.vehicles:
                    state = vehicle.state
                    print(
                        f"{vehicle.id:12} {state.mode if state else '?':10} "
                        f"armed={state and state.armed} alt={state and state.alt_rel} "
                        f"battery={state and state.battery_remaining}%"
                    )
                    updates += 1
                if args.updates is not None and updates >= args.updates:
                    return


try:
    asyncio.run(watch())
except HubError as error:
    raise SystemExit(f"error: {error}") from None
