import { describe, expect, it } from "vitest";
import * as mav from "../generated/mavlink";
import { CMD, makeItem } from "./model";
import { takeoffHeight } from "./startHeight";

describe("takeoffHeight", () => {
  it("takes the take-off item's height", () => {
    const items = [makeItem(CMD.WAYPOINT, 1, 1, 30), makeItem(CMD.TAKEOFF, 0, 0, 12)];
    expect(takeoffHeight(items, null)).toEqual({ metres: 12, from: "item 2" });
  });

  it("else the first placed item's", () => {
    const items = [makeItem(CMD.CHANGE_SPEED), makeItem(CMD.WAYPOINT, 1, 1, 25)];
    expect(takeoffHeight(items, null)).toEqual({ metres: 25, from: "item 2" });
  });

  it("turns a height above sea level into one above home", () => {
    const item = { ...makeItem(CMD.TAKEOFF, 0, 0, 120), frame: mav.MAV_FRAME_GLOBAL };
    expect(takeoffHeight([item], 100)).toEqual({ metres: 20, from: "item 1" });
    expect(takeoffHeight([item], null)).toHaveProperty("refused");
  });

  it("never makes a missing or terrain height into 0", () => {
    const empty = { ...makeItem(CMD.TAKEOFF), alt: null as unknown as number };
    expect(takeoffHeight([empty], 0)).toEqual({ refused: "item 1 has no altitude" });
    const terrain = { ...makeItem(CMD.TAKEOFF, 0, 0, 10), frame: mav.MAV_FRAME_GLOBAL_TERRAIN_ALT };
    expect(takeoffHeight([terrain], 0)).toHaveProperty("refused");
    expect(takeoffHeight([makeItem(CMD.TAKEOFF, 0, 0, 0)], 0)).toHaveProperty("refused");
    expect(takeoffHeight([], 0)).toHaveProperty("refused");
  });
});
