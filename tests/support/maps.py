"""The dashboard's map as pixels: where a point is drawn, and checks that the map is open."""

from __future__ import annotations

import contextlib

from playwright.sync_api import FloatRect, Page, expect

from tests.support.waiting import poll_until


def _box(page: Page, selector: str) -> FloatRect:
    box = page.locator(selector).first.bounding_box()
    assert box is not None, f"{selector} is not on the page"
    return box


OPEN_MAP_JS = """([x, y]) => {
    const element = document.elementFromPoint(x, y);
    if (element === null) return "nothing";
    if (element.closest(".mission-panel, .leaflet-control, .drawer-toggles, .leaflet-popup"))
        return "a panel";
    if (element.closest(".vehicle-marker, .mission-item")) return "a marker";
    return element.closest("#map") ? "map" : element.tagName;
}"""


def _on_open_map(page: Page, x: float, y: float) -> bool:
    return bool(page.evaluate(OPEN_MAP_JS, [x, y]) == "map")


def _assert_on_open_map(page: Page, x: float, y: float) -> None:
    """A point to click or drag on the map: on the map, not under a panel or control."""
    hit = page.evaluate(OPEN_MAP_JS, [x, y])
    assert hit == "map", f"({x:.0f}, {y:.0f}) is on {hit}, not the open map"


def _latlon_at(page: Page, x: float, y: float) -> tuple[float, float]:
    """What the map's pointer readout says at (x, y): moved off and back, so that it
    reads the map as it is now, not as it was under a pointer that stood still. On a
    loaded machine the readout lags the pointer, so the reading waits (3 s at most) for
    the text to change from what it said before the move; unchanged, the place is the
    same as before and the map has not moved."""
    readout = page.locator('[data-field="cursor-position"]')
    before = readout.inner_text() if readout.is_visible() else ""
    page.mouse.move(x + 2, y)
    page.mouse.move(x, y)
    expect(readout).to_be_visible()
    with contextlib.suppress(AssertionError):
        expect(readout).not_to_have_text(before, timeout=3_000)
    lat, lon = (float(part) for part in readout.inner_text().split(","))
    return lat, lon


class PixelMap:
    """Page pixels from lat/lon and back, read off the map's own pointer readout at two
    open points (Web Mercator is linear enough over the few hundred metres drawn here).
    Waits for the map to stop moving: a pan or zoom animates."""

    def __init__(self, page: Page, settle_s: float = 15) -> None:
        area = _box(page, "#map")
        grid = [
            (area["x"] + area["width"] * fx / 10, area["y"] + area["height"] * fy / 10)
            for fx in range(1, 10)
            for fy in range(2, 10)
        ]
        open_points = [p for p in grid if _on_open_map(page, *p)]
        assert len(open_points) >= 2, "no open map to read positions from"
        self.a, self.b = max(
            ((p, q) for p in open_points for q in open_points),
            key=lambda pq: min(abs(pq[0][0] - pq[1][0]), abs(pq[0][1] - pq[1][1])),
        )
        readings: list[tuple[tuple[float, float], ...]] = [()]

        def settled() -> bool:
            now = (_latlon_at(page, *self.a), _latlon_at(page, *self.b))
            same = now == readings[0]
            readings[0] = now
            return same

        poll_until(settled, settle_s, "the map to settle", every_s=0.3)
        (lat_a, lon_a), (lat_b, lon_b) = readings[0]
        self.lat0, self.lon0 = lat_a, lon_a
        self.per_lon = (self.b[0] - self.a[0]) / (lon_b - lon_a)
        self.per_lat = (self.b[1] - self.a[1]) / (lat_b - lat_a)

    def pixel(self, lat: float, lon: float) -> tuple[float, float]:
        return (
            self.a[0] + (lon - self.lon0) * self.per_lon,
            self.a[1] + (lat - self.lat0) * self.per_lat,
        )

    def metres_per_px(self) -> float:
        return 111_320.0 / abs(self.per_lat)


def long_press(page: Page, x: float, y: float, until: str) -> None:
    """A finger held on the screen (CDP touch events, as a touch screen sends them)
    until ``until`` shows, then lifted: no fixed wait for the long-press timer."""
    cdp = page.context.new_cdp_session(page)
    point = [{"x": x, "y": y}]
    cdp.send("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": point})
    try:
        expect(page.locator(until)).to_be_visible(timeout=10_000)
    finally:
        cdp.send("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
        cdp.detach()
