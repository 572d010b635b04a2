"""Sensors the agent reads besides the flight controller: the LIDAR's scan sources."""
