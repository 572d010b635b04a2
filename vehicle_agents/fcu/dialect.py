"""The MAVLink dialect the agent speaks, fixed where the agent builds its link."""

from __future__ import annotations

import os
import sys
from typing import Any

from protocol import mavlink_extra

DIALECT = "ardupilotmega"
UNUSED_ON_IMPORT = "pymavlink.dialects.v10.all"


def mavutil() -> Any:
    """pymavlink's `mavutil`, speaking MAVLink 2 in the ArduPilot dialect.

    `mavutil` picks its dialect from the environment when it is first imported: left alone,
    it loads "all" and loads it again for MAVLink 2 on the first frame (about 6 MB more on
    a small board), and its messages would come from another module than the dialect the
    agent decodes with. So nothing in the agent imports it at module level; the link and
    the mode tables ask for it here, and it always speaks MAVLink 2 in that dialect.
    """
    os.environ.setdefault("MAVLINK20", "1")
    os.environ.setdefault("MAVLINK_DIALECT", DIALECT)
    if "pymavlink.mavutil" not in sys.modules:
        # mavutil also imports the MAVLink 1 "all" dialect if it is there (for PyInstaller;
        # it carries on without it). The agent never uses it: leaving it out saves about
        # 5.4 MB of RSS. None in sys.modules makes that one import fail, as it does where
        # the dialect is not installed.
        sys.modules.setdefault(UNUSED_ON_IMPORT, None)  # type: ignore[arg-type]
    from pymavlink import mavutil as module

    if module.current_dialect != DIALECT or not module.mavlink20():
        # Imported earlier by someone else in this process (a test, an embedding tool), on
        # another dialect or MAVLink 1: the agent's messages must be the ones it decodes.
        os.environ["MAVLINK20"] = "1"
        module.set_dialect(DIALECT)
    return module


# The standard-modes messages (AVAILABLE_MODES, CURRENT_MODE, AVAILABLE_MODES_MONITOR) and
# COMPONENT_METADATA, which the ArduPilot dialect the agent decodes with lacks: defined in
# `protocol.mavlink_extra` rather than taken from pymavlink's development dialect, whose
# import would cost a small board several MB for three messages.
mavlink_extra.register()
