from __future__ import annotations

from collections.abc import Iterator

import pytest

from backend.viz3d.server import VizServer


@pytest.fixture
def viz() -> Iterator[VizServer]:
    """A real viser server on a free port, for the 3D view's tests."""
    started = VizServer.start()
    yield started
    started.stop()
