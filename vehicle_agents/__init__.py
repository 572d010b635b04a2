"""The vehicle agent: bridges one flight controller (MAVLink) to the hub (WebSocket).

It knows MAVLink and the hub protocol, and nothing of FastAPI or SQLAlchemy, so it can
run on boards as small as a Raspberry Pi Zero 2 W.
"""

import os

# Before anything imports pymavlink.mavutil: left alone, it picks the "all" dialect and
# loads it again for MAVLink 2 on the first frame (about 6 MB more on a small board),
# and its messages would come from another module than the ArduPilot dialect the agent
# speaks. An operator's own MAVLINK_DIALECT still wins.
os.environ.setdefault("MAVLINK20", "1")
os.environ.setdefault("MAVLINK_DIALECT", "ardupilotmega")

__version__ = "0.1.0"
