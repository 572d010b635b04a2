"""The vehicle agent: bridges one flight controller (MAVLink) to the hub (WebSocket).

It knows MAVLink and the hub protocol, and nothing of FastAPI or SQLAlchemy, so it can
run on boards as small as a Raspberry Pi Zero 2 W.
"""

__version__ = "0.1.0"
