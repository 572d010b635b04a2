"""Log in, say who we are, and list the fleet; optionally make a scoped API token.

    GCS_HUB=http://127.0.0.1:8000 GCS_USERNAME=admin GCS_PASSWORD=... \\
        python examples/01_log_in_and_list_the_fleet.py [--api-token NAME [--scopes read]]

With --api-token it prints an API token for later runs (export GCS_TOKEN=...), limited to
the given scopes (read, command, audit, admin; all of yours by default). API tokens expire
after 90 days unless made otherwise (docs/security.md).

Every example uses the client package (gcs_client, docs/client.md) and reads the hub's
address and credentials from GCS_HUB, and GCS_TOKEN or GCS_USERNAME and GCS_PASSWORD. Any
error ends it with the reason and exit status 1.
"""

import argparse

from gcs_client import HubError, SyncHub

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--api-token", metavar="NAME", help="make an API token with this name")
parser.add_argument("--scopes", nargs="+", help="what the token may do (default: all you may)")
args = parser.parse_args()

try:
    with SyncHub.from_env() as hub:
        me = hub.auth.me()
        print(f"logged in as {me.username} ({me.role}): {', '.join(me.permissions)}")

        for vehicle in hub.vehicles.list():
            state = vehicle.state
            link = "online" if vehicle.connected else "offline"
            mode = state.mode if state else "?"
            print(
                f"{vehicle.id:12} {vehicle.autopilot:9} {link:7} {mode:10}"
                f" armed={state and state.armed} alt={state and state.alt_rel}"
            )

        if args.api_token:
            issued = hub.auth.create_api_token(args.api_token, args.scopes)
            print(f"API token {issued.name!r} with scopes {', '.join(issued.scopes)}:")
            print(f"export GCS_TOKEN={issued.token}")
except HubError as error:
    raise SystemExit(f"error: {error}") from None
