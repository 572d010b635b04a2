"""The 3D view's note on positions it did not draw, in an operator's words.

``SceneFrame`` counts each position it will not place, by reason. A bare count ("39 too
far from the origin") tells an operator nothing they can act on: what the origin is,
how far is too far, and what to do. The origin is fixed for as long as the hub runs
(every layer is drawn in its metres), so the way to move it is GCS_VIZ_ORIGIN.
"""

from __future__ import annotations

from collections.abc import Mapping

from backend.viz3d.frame import MAX_ALT_M, MAX_RANGE_M, MIN_ALT_M
from common.geodesy import GeoPoint

ORIGIN_SETTING = "GCS_VIZ_ORIGIN"

# Per reason (SceneFrame.skipped's keys): what those positions were, and what to do.
_WHY = {
    "no origin yet": (
        "arrived before any vehicle reported its home position",
        "they are drawn once one does.",
    ),
    "no altitude": (
        "came without an altitude",
        "the vehicle is drawn once its autopilot reports one.",
    ),
    "not a number": (
        "had a missing number (NaN) for latitude, longitude or altitude",
        "most likely a GPS without a fix.",
    ),
    "out of range": (
        f"were outside any real position (altitude below {MIN_ALT_M:,.0f} m or "
        f"above {MAX_ALT_M:,.0f} m above sea level)",
        "most likely a bad GPS fix.",
    ),
}


def _origin_text(origin: GeoPoint | None, configured: bool) -> str:
    if origin is None:
        return "the first home position a vehicle reports"
    where = f"{origin.lat:.5f}, {origin.lon:.5f}"
    if configured:
        return f"{where}, set by {ORIGIN_SETTING}"
    return f"{where}, the first home position the fleet reported when the hub started"


def skipped_note(skipped: Mapping[str, int], origin: GeoPoint | None, configured: bool) -> str:
    """Markdown for the 3D view's panel: one paragraph per reason, empty when none."""
    paragraphs = []
    for reason, count in sorted(skipped.items()):
        positions = "1 position" if count == 1 else f"{count} positions"
        if reason == "too far from the origin":
            paragraphs.append(
                f"**Not drawn: {positions} more than {MAX_RANGE_M / 1000:,.0f} km from the "
                f"3D view's origin** ({_origin_text(origin, configured)}). The 3D view draws "
                "in metres around that point, and it stays there while the hub runs. They "
                "belong to something far from the rest of the fleet (a vehicle, a mission, a "
                "survey or a replayed flight), or are bad GPS fixes. To centre the 3D view "
                f"elsewhere, restart the hub with {ORIGIN_SETTING}=latitude,longitude of the "
                "place you fly."
            )
        else:
            what, action = _WHY.get(reason, (reason, ""))
            paragraphs.append(f"**Not drawn: {positions}** that {what}: {action}".rstrip(": "))
    return "\n\n".join(paragraphs)
