"""A client's scan subscription: newest wins per vehicle, for the vehicles it asked for.

The live feed (``backend.realtime.client_feed``) holds one per client; it asks the hub
for it (``FeedServices.scan_subscription``) and uses it as the ``ScanFeedSubscription``
it declares, so realtime never imports the scans feature."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from backend.realtime.bus import LatestSubscription


class ScanSubscription(LatestSubscription):
    def __init__(self) -> None:
        super().__init__()
        self.vehicles: set[str] = set()

    def offer(self, key: Hashable, message: Any) -> bool:
        if key in self.vehicles:
            super().offer(key, message)
        return True  # another vehicle's scan: not wanted, never waited for

    @property
    def pending(self) -> int:
        """Scans waiting for this feed: at most one per subscribed vehicle."""
        return len(self._pending)
