import type * as L from "leaflet";
import { describe, expect, it } from "vitest";
import { LONG_MISSION, type PlacedItem, numberedItems } from "./lanes";
import { CMD, makeItem } from "./model";

/** A survey's path: `lanes` east-west lanes 30 m apart, four waypoints along each. */
function survey(lanes: number): PlacedItem[] {
  const placed: PlacedItem[] = [];
  const metre = 1 / 111_000;
  for (let lane = 0; lane < lanes; lane++) {
    const xs = [0, 20, 180, 200];
    for (const x of lane % 2 === 0 ? xs : [...xs].reverse()) {
      const at = { lat: lane * 30 * metre, lng: x * metre } as L.LatLng;
      placed.push({ item: makeItem(CMD.WAYPOINT, at.lat, at.lng, 20), seq: placed.length + 1, at, key: false, movable: true });
    }
  }
  return placed;
}

/** Metres on the screen at `metresPerPixel`. */
const pixels = (metresPerPixel: number) => (at: L.LatLng) => ({ x: (at.lng * 111_000) / metresPerPixel, y: (-at.lat * 111_000) / metresPerPixel });

describe("numberedItems", () => {
  it("numbers every item of a short mission", () => {
    const placed = survey(2);
    expect(placed.length).toBeLessThanOrEqual(LONG_MISSION);
    expect(numberedItems(placed, pixels(1)).size).toBe(placed.length);
  });

  it("numbers a long survey's ends and turns only, never the points along a lane", () => {
    const placed = survey(12); // 48 places
    const numbered = numberedItems(placed, pixels(0.5));
    // The turnarounds (first and last of each lane), not the camera's entry and exit.
    expect([...numbered].sort((a, b) => a - b)).toEqual(placed.filter((_, i) => i % 4 === 0 || i % 4 === 3).map((p) => p.seq));
  });

  it("leaves crowded turns for a closer zoom", () => {
    const placed = survey(12);
    const far = numberedItems(placed, pixels(5)); // lanes 6 px apart
    const near = numberedItems(placed, pixels(0.5));
    expect(far.has(1)).toBe(true);
    expect(far.has(placed.length)).toBe(true);
    expect(far.size).toBeLessThan(near.size);
  });

  it("always numbers the active item and a refused one", () => {
    const placed = survey(12);
    placed[5].key = true;
    expect(numberedItems(placed, pixels(5)).has(6)).toBe(true);
  });
});
