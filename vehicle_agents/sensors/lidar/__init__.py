"""Serial 2-D LIDARs, parsed from each manufacturer's published wire format.

- `common`: the packet, drop counters, the A5 5A answer descriptor, the buffer rules.
- `rplidar`: Slamtec RPLIDAR A1/A2/A3/C1/S1/S2 (standard nodes, express capsules).
- `ydlidar`: YDLIDAR X2/X4/G4 (2-byte samples) and T-mini Pro (3-byte samples).
- `ldlidar`: LDROBOT LD06, LD19, STL-27L (47-byte packets with CRC-8).
- `models`: model -> family, wire format, default baud, wiring; start and stop commands.
- `probe`: `gcs-agent lidar-probe DEVICE`, which finds the family and baud of a sensor.
"""
