"""Download a flight: the newest one, or one vehicle's newest, as GeoJSON, CSV or .tlog.

    GCS_HUB=http://127.0.0.1:8000 GCS_TOKEN=... \\
        python examples/05_export_a_flight.py [--vehicle ID] [--format geojson] [--output DIR]

The hub finds flights (arm to disarm) by itself. A .tlog opens in QGroundControl,
MAVProxy and pymavlink's mavlogdump.py.
"""

import argparse
from pathlib import Path

from gcs_client import HubError, SyncHub

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--vehicle", help="a vehicle id (default: any)")
parser.add_argument("--format", choices=["geojson", "csv", "tlog"], default="geojson")
parser.add_argument("--output", type=Path, default=Path.cwd(), help="folder to write to")
args = parser.parse_args()

# Said before asking the hub anything: a flight is not downloaded to be thrown away.
if not args.output.is_dir():
    raise SystemExit(f"error: the output folder {args.output} does not exist")

try:
    with SyncHub.from_env() as hub:
        page = hub.flights.list(args.vehicle)  # newest first
        flights = [flight for flight in page.flights if flight.end_time is not None]
        if not flights:
            raise SystemExit("error: no finished flight yet (fly one: 03_command_a_vehicle.py)")
        flight = flights[0]
        print(
            f"flight {flight.id} of {flight.vehicle_id}: {flight.duration_s or 0:.0f} s, "
            f"{flight.distance_m or 0:.0f} m, up to {flight.max_alt_m or 0:.1f} m"
        )
        path = args.output / f"{flight.vehicle_id}_flight{flight.id}.{args.format}"
        hub.flights.export(flight.id, args.format, path)  # streamed to the file
        print(f"wrote {path} ({path.stat().st_size} bytes)")
except HubError as error:
    raise SystemExit(f"error: {error}") from None
