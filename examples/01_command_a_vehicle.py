"""List the fleet and take the first vehicle off to 10 m.

python examples/01_command_a_vehicle.py http://127.0.0.1:8000
"""

import sys

import httpx

base = sys.argv[1] if len(sys.argv) > 1 else "http://127.0.0.1:8000"
with httpx.Client(base_url=base, timeout=30) as api:
    vehicles = api.get("/api/v1/vehicles").json()
    for vehicle in vehicles:
        state = vehicle["state"] or {}
        print(f"{vehicle['id']:12} {state.get('mode', '?'):10} alt {state.get('alt_rel')}")
    target = vehicles[0]["id"]
    answer = api.post(
        f"/api/v1/vehicles/{target}/commands", json={"name": "takeoff", "altitude": 10}
    )
    print(target, "takeoff:", answer.json()["outcome"]["message"])
