"""Which listening addresses stay on this machine: shared by the hub and the launcher."""

from __future__ import annotations

import ipaddress

# Addresses that mean "every interface".
WILDCARDS = frozenset({"0.0.0.0", "::", ""})


def is_loopback(host: str) -> bool:
    """Only this machine can reach ``host`` (a name other than localhost may resolve to
    anything, so it counts as the network)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False
