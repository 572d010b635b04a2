"""LIDAR scans on the hub: checked, stored, turned into world points, mapped, fanned out."""
