"""The MAVLink dialect the agent speaks, fixed where the agent builds its link."""

from __future__ import annotations

import os
import sys
from typing import Any

from protocol import mavlink_extra as component_metadata

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


# MAVLink's standard-modes messages (AVAILABLE_MODES 435, CURRENT_MODE 436,
# AVAILABLE_MODES_MONITOR 437), which PX4 (1.15 on) and ArduPilot (4.7 on) send. pymavlink
# 2.4.50 keeps them in its development dialect only, so the ArduPilot dialect the agent
# decodes with would drop them as unknown; its decoder looks each id up in the module's
# ``mavlink_map``, and the development dialect's classes pack and unpack the same bytes.
STANDARD_MODES_IDS = (435, 436, 437)


def teach_standard_modes() -> None:
    """Make the agent's dialect decode the standard-modes messages (idempotent)."""
    from pymavlink.dialects.v20 import ardupilotmega, development

    for message_id in STANDARD_MODES_IDS:
        ardupilotmega.mavlink_map.setdefault(message_id, development.mavlink_map[message_id])
    component_metadata.register()  # COMPONENT_METADATA, which no pymavlink dialect has


teach_standard_modes()
