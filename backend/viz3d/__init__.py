"""The 3D view: a viser scene on loopback that mirrors the fleet, relayed under /viz/."""
