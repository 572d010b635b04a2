import { describe, expect, it } from "vitest";
import { Store, changedValues } from "./store";

interface State {
  count: number;
  name: string;
  tags: readonly string[];
}

const initial = (): State => ({ count: 0, name: "a", tags: [] });

describe("Store", () => {
  it("tells a subscriber when its slice changes, with the new and old values", () => {
    const store = new Store(initial());
    const seen: [number, number][] = [];
    store.subscribe((state) => state.count, (now, before) => seen.push([now, before]));
    store.set({ count: 1 });
    store.set({ count: 2 });
    expect(seen).toEqual([
      [1, 0],
      [2, 1],
    ]);
    expect(store.state.count).toBe(2);
  });

  it("does not tell a subscriber of changes to other slices", () => {
    const store = new Store(initial());
    let calls = 0;
    store.subscribe((state) => state.name, () => calls++);
    store.set({ count: 5 });
    store.set({ tags: ["x"] });
    store.set({ name: "a" }); // the same value: no change
    expect(calls).toBe(0);
    store.set({ name: "b" });
    expect(calls).toBe(1);
  });

  it("tells by identity: a new array is a change, the same one is not", () => {
    const store = new Store(initial());
    let calls = 0;
    store.subscribe((state) => state.tags, () => calls++);
    const tags = ["x"];
    store.set({ tags });
    store.set({ tags });
    expect(calls).toBe(1);
  });

  it("takes the subscriber's own test of sameness", () => {
    const store = new Store(initial());
    let calls = 0;
    store.subscribe(
      (state) => state.tags,
      () => calls++,
      { equals: (a, b) => a.join() === b.join() },
    );
    store.set({ tags: [] });
    store.set({ tags: ["x"] });
    store.set({ tags: ["x"] });
    expect(calls).toBe(1);
  });

  it("calls at once when asked, and never after unsubscribing or closing", () => {
    const store = new Store(initial());
    const seen: number[] = [];
    const unsubscribe = store.subscribe((state) => state.count, (now) => seen.push(now), { now: true });
    expect(seen).toEqual([0]);
    unsubscribe();
    store.set({ count: 1 });
    expect(seen).toEqual([0]);

    store.subscribe((state) => state.count, (now) => seen.push(now));
    store.close();
    store.set({ count: 2 });
    expect(seen).toEqual([0]);
  });

  it("tells every subscriber of the newest state when a listener sets again", () => {
    const store = new Store(initial());
    const names: string[] = [];
    const counts: number[] = [];
    store.subscribe((state) => state.count, (count) => store.set({ name: `n${count}` }));
    store.subscribe((state) => state.name, (name) => names.push(name));
    store.subscribe((state) => state.count, (count) => counts.push(count));
    store.set({ count: 1 });
    expect(names).toEqual(["n1"]);
    expect(counts).toEqual([1]); // once, not once per pass
  });
});

describe("changedValues", () => {
  it("lists the new and replaced values, not the kept or removed ones", () => {
    const kept = { v: 1 };
    const before = new Map([
      ["kept", kept],
      ["replaced", { v: 2 }],
      ["removed", { v: 3 }],
    ]);
    const replacement = { v: 20 };
    const added = { v: 4 };
    const now = new Map([
      ["kept", kept],
      ["replaced", replacement],
      ["added", added],
    ]);
    expect(changedValues(now, before)).toEqual([replacement, added]);
  });
});
