import { describe, expect, it } from "vitest";
import { DEFAULT_SHARE, KEY_STEP, MAX_SHARE, MIN_SHARE, STORAGE_KEY, loadShare, saveShare, shareAfterKey } from "./splitShare";

function memory(initial: Record<string, string> = {}) {
  const values = new Map(Object.entries(initial));
  return {
    getItem: (key: string) => values.get(key) ?? null,
    setItem: (key: string, value: string) => void values.set(key, value),
  };
}

describe("the 3D view's split", () => {
  it("starts at half, beside the map, with nothing or nonsense stored", () => {
    expect(loadShare(memory())).toEqual({ share: DEFAULT_SHARE, full: false });
    expect(loadShare(memory({ [STORAGE_KEY]: "{not json" }))).toEqual({ share: DEFAULT_SHARE, full: false });
    expect(loadShare(memory({ [STORAGE_KEY]: '{"share":"wide"}' }))).toEqual({ share: DEFAULT_SHARE, full: false });
  });

  it("comes back as it was left, kept within a fifth of either side", () => {
    const storage = memory();
    saveShare({ share: 0.35, full: true }, storage);
    expect(loadShare(storage)).toEqual({ share: 0.35, full: true });
    saveShare({ share: 0.99, full: false }, storage);
    expect(loadShare(storage).share).toBe(MAX_SHARE);
  });

  it("moves with the arrow keys: left widens the 3D view, Home and End go to the ends", () => {
    expect(shareAfterKey(0.5, "ArrowLeft")).toBeCloseTo(0.5 + KEY_STEP);
    expect(shareAfterKey(0.5, "ArrowRight")).toBeCloseTo(0.5 - KEY_STEP);
    expect(shareAfterKey(MAX_SHARE, "ArrowLeft")).toBe(MAX_SHARE);
    expect(shareAfterKey(0.5, "Home")).toBe(MAX_SHARE);
    expect(shareAfterKey(0.5, "End")).toBe(MIN_SHARE);
    expect(shareAfterKey(0.5, "Enter")).toBeNull();
  });
});
