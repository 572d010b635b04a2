"""The LIDARs `gcs demo --lidar NAME` can fit: each a wire format the simulator speaks and
the agent's parser for it reads (kept apart from the launcher so that the command line
lists them without importing it)."""

from __future__ import annotations

from typing import NamedTuple


class DemoLidar(NamedTuple):
    wire: str  # the simulator's --lidar-format
    model: str  # the agent's --lidar-model
    scan_mode: int = 0  # the agent's --lidar-scan-mode (RPLIDAR: 0 standard, N express)


# `gcs demo --lidar NAME`: each name a wire format the agent's parsers read.
DEMO_LIDARS = {
    "ydlidar": DemoLidar("ydlidar", "ydlidar-tmini-pro"),
    "ydlidar-x4": DemoLidar("ydlidar-x4", "ydlidar-x4"),
    "ydlidar-g4": DemoLidar("ydlidar-g4", "ydlidar-g4"),
    "rplidar": DemoLidar("rplidar", "rplidar-a1"),
    "rplidar-express": DemoLidar("rplidar-express", "rplidar-a1", 1),
    "rplidar-dense": DemoLidar("rplidar-dense", "rplidar-c1", 1),
    "rplidar-ultra": DemoLidar("rplidar-ultra", "rplidar-a3", 3),
    "ld06": DemoLidar("ld06", "ld06"),
    "ld19": DemoLidar("ld06", "ld19"),
    "stl27l": DemoLidar("ld06", "stl27l"),
}

DEMO_LIDAR_NAMES = tuple(DEMO_LIDARS)
# `gcs demo --lidar` with no name: the YDLIDAR T-mini Pro's format, the lightest to parse.
DEFAULT_DEMO_LIDAR = "ydlidar"
