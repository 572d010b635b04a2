"""Point clouds out as PLY, for CloudCompare, PDAL and MeshLab, through plyfile."""

from __future__ import annotations

import io

import numpy as np
from plyfile import PlyData, PlyElement  # type: ignore[import-untyped]

from backend.scans.points import Array


def ply_bytes(enu: Array, comment: str) -> bytes:
    """A binary little-endian PLY of x (east), y (north), z (up) metres as float64:
    centimetres survive kilometres from the origin."""
    vertices = np.empty(len(enu), dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8")])
    if len(enu):
        vertices["x"], vertices["y"], vertices["z"] = enu[:, 0], enu[:, 1], enu[:, 2]
    data = PlyData([PlyElement.describe(vertices, "vertex")], text=False, comments=[comment])
    out = io.BytesIO()
    data.write(out)
    return out.getvalue()
