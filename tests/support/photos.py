"""Photos a camera uploads, and the hub's answer to them."""

from __future__ import annotations

import socket

CAMERA_MODEL = "4.8,3.6,320,240,5.4"  # a small sensor and image: fast to render and send


GROUND_BELOW_M = 30.0


def _accepts(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=1).close()
    except OSError:
        return False
    return True
