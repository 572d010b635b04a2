"""Log in, say who we are, and list the fleet; optionally make a scoped API token.

    GCS_HUB=http://127.0.0.1:8000 GCS_USERNAME=admin GCS_PASSWORD=... \\
        python examples/01_log_in_and_list_the_fleet.py [--api-token NAME [--scopes read]]

With --api-token it prints a long-lived token for later runs (export GCS_TOKEN=...),
limited to the given scopes (read, command, audit, admin; all of yours by default).
"""

import argparse

from hubclient import check, connect

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--api-token", metavar="NAME", help="make an API token with this name")
parser.add_argument("--scopes", nargs="+", help="what the token may do (default: all you may)")
args = parser.parse_args()

with connect() as api:
    me = check(api.get("/api/v1/auth/me"))
    print(f"logged in as {me['username']} ({me['role']}): {', '.join(me['permissions'])}")

    for vehicle in check(api.get("/api/v1/vehicles")):
        state = vehicle["state"] or {}
        link = "online" if vehicle["connected"] else "offline"
        print(
            f"{vehicle['id']:12} {vehicle['autopilot']:9} {link:7} {state.get('mode', '?'):10}"
            f" armed={state.get('armed')} alt={state.get('alt_rel')}"
        )

    if args.api_token:
        body = {"name": args.api_token, "scopes": args.scopes}
        issued = check(api.post("/api/v1/auth/api-tokens", json=body))
        print(f"API token {issued['name']!r} with scopes {', '.join(issued['scopes'])}:")
        print(f"export GCS_TOKEN={issued['token']}")
