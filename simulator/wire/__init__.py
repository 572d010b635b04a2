"""The bytes the simulated LIDAR sends on its serial line, in each model's format:
what the formats share and which exist (`formats`), and `ldlidar`, `rplidar`, `ydlidar`."""
