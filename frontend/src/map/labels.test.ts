import { describe, expect, it } from "vitest";
import { type LabelBox, placeLabels } from "./labels";

const box = (id: string, x: number, y: number, priority = 0, width = 40, height = 12): LabelBox => ({
  id,
  x,
  y,
  width,
  height,
  priority,
});

describe("placeLabels", () => {
  it("shows every label that overlaps none", () => {
    const layout = placeLabels([box("a", 0, 0), box("b", 100, 0), box("c", 0, 100)]);
    expect(layout).toEqual(
      new Map([
        ["a", []],
        ["b", []],
        ["c", []],
      ]),
    );
  });

  it("merges an overlapping label into the one placed first, by id when priorities tie", () => {
    const layout = placeLabels([box("drone-b", 10, 5), box("drone-a", 0, 0), box("drone-c", 20, 0)]);
    expect(layout).toEqual(new Map([["drone-a", ["drone-b", "drone-c"]]]));
  });

  it("places the higher priority (the selected vehicle) first", () => {
    const layout = placeLabels([box("a", 0, 0), box("selected", 5, 5, 1)]);
    expect(layout).toEqual(new Map([["selected", ["a"]]]));
  });

  it("counts boxes that only touch as apart", () => {
    const layout = placeLabels([box("a", 0, 0), box("b", 40, 0), box("c", 0, 12)]);
    expect([...layout.keys()].sort()).toEqual(["a", "b", "c"]);
  });

  it("finds overlaps across grid cells", () => {
    // 96 px cells: b starts in the next cell but overlaps a, which spans both.
    const layout = placeLabels([box("a", 80, 80, 1, 40, 40), box("b", 100, 100)]);
    expect(layout).toEqual(new Map([["a", ["b"]]]));
  });

  it("places a crowd of a thousand quickly, each label shown or merged once", () => {
    const boxes = Array.from({ length: 1000 }, (_, i) => box(`v${i}`, (i * 37) % 1900, (i * 53) % 1000));
    const layout = placeLabels(boxes);
    const all = [...layout.entries()].flatMap(([id, merged]) => [id, ...merged]);
    expect(all.sort()).toEqual(boxes.map((b) => b.id).sort());
  });
});
