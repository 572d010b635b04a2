"""Reading tlogs with mavutil without leaking its global state into other tests.

``mavutil.mavlink_connection`` switches the whole module to MAVLink 2 when it meets
a MAVLink 2 packet, by setting ``MAVLINK20`` in ``os.environ`` and replacing the
module-global dialect. Starting in MAVLink 2 under ``monkeypatch`` makes the switch
a no-op and puts everything back after the test.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest


def mavutil_in_mavlink2(monkeypatch: pytest.MonkeyPatch) -> ModuleType:
    from pymavlink import mavutil

    monkeypatch.setenv("MAVLINK20", "1")
    dialect = importlib.import_module(f"pymavlink.dialects.v20.{mavutil.current_dialect}")
    monkeypatch.setattr(mavutil, "mavlink", dialect)
    module: ModuleType = mavutil
    return module


def read_tlog(mavutil: ModuleType, path: Path) -> list[Any]:
    """Every message of a .tlog, in order, as pymavlink (and so other GCS tools) reads it."""
    connection = mavutil.mavlink_connection(str(path))
    messages = []
    try:
        while (message := connection.recv_match()) is not None:
            messages.append(message)
    finally:
        connection.close()
    return messages
