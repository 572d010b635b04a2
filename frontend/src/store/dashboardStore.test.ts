import { describe, expect, it } from "vitest";
import type { LeaseRefusal, LeaseState, LiveEvent, SurveyUpdate } from "../generated/protocol";
import type { VehicleSummary } from "../hub/types";
import { DashboardStore } from "./dashboardStore";

const vehicle = (id: string) => ({ id }) as VehicleSummary;
const lease = (vehicle_id: string, holder: string | null) => ({ type: "lease", vehicle_id, holder }) as LeaseState;

describe("DashboardStore", () => {
  it("hands a fleet view the removed vehicles, then the changed ones", () => {
    const store = new DashboardStore();
    const calls: string[] = [];
    store.followFleet({
      update: (changed) => calls.push(`update ${[...changed].map((v) => v.id).join(",")}`),
      remove: (id) => calls.push(`remove ${id}`),
    });
    store.setFleet({ changed: [vehicle("a"), vehicle("b")], removed: ["c"], all: new Map() });
    expect(calls).toEqual(["remove c", "update a,b"]);
  });

  it("tells selection subscribers of every pick, and id subscribers of a new vehicle only", () => {
    const store = new DashboardStore();
    const picks: [string | null, boolean][] = [];
    const ids: (string | null)[] = [];
    store.subscribe((state) => state.selection, ({ id, pan }) => picks.push([id, pan]));
    store.subscribe((state) => state.selection.id, (id) => ids.push(id));
    store.select("a", false);
    store.select("a", true);
    store.select("b", true);
    expect(picks).toEqual([
      ["a", false],
      ["a", true],
      ["b", true],
    ]);
    expect(ids).toEqual(["a", "b"]);
  });

  it("keeps the event log: a batch once, a resent event not again, a note when the hub dropped some", () => {
    const store = new DashboardStore();
    const logs: number[] = [];
    store.subscribe((state) => state.events, (events) => logs.push(events.length));
    const event = { vehicle_id: "a", time: 10, kind: "statustext", severity: 6, text: "hello" } as LiveEvent;
    store.onEventBatch({ type: "events", events: [event], dropped: 0 }, 11);
    store.onEventBatch({ type: "events", events: [event], dropped: 0 }, 12);
    expect(logs).toEqual([1]);
    store.onEventBatch({ type: "events", events: [], dropped: 3 }, 13);
    expect(logs).toEqual([1, 2]);
    const note = store.state.events[1];
    expect(note).toMatchObject({ vehicleId: "hub", kind: "dropped", time: 13, severity: 4 });
    expect(note.text).toContain("3 less severe events");
  });

  it("bounds the event log", () => {
    const store = new DashboardStore(2);
    store.addEvents([1, 2, 3].map((time) => ({ vehicle_id: "a", time, kind: "k", text: `t${time}` })));
    expect(store.state.events.map((e) => e.time)).toEqual([2, 3]);
  });

  it("keeps the latest lease and survey of each, as new maps so subscribers see the change", () => {
    const store = new DashboardStore();
    const leaseMaps: ReadonlyMap<string, LeaseState>[] = [];
    store.subscribe((state) => state.leases, (now) => leaseMaps.push(now));
    store.putLease(lease("a", "ann"));
    store.putLease(lease("b", null));
    store.putLease(lease("a", null));
    expect(leaseMaps).toHaveLength(3);
    expect(store.state.leases.get("a")?.holder).toBeNull();
    expect(store.state.leases.get("b")?.holder).toBeNull();
    expect(leaseMaps[0].get("a")?.holder).toBe("ann"); // an earlier map is never changed

    const survey = { type: "survey", survey_id: "s1", state: "flying" } as SurveyUpdate;
    store.putSurvey(survey);
    expect(store.state.surveys.get("s1")).toBe(survey);
  });

  it("keeps a refusal until it is cleared, and clearing nothing tells nobody", () => {
    const store = new DashboardStore();
    let calls = 0;
    store.subscribe((state) => state.refusals, () => calls++);
    store.putRefusal({ type: "lease_refused", vehicle_id: "a", reason: "busy" } as LeaseRefusal);
    expect(store.state.refusals.get("a")?.reason).toBe("busy");
    store.clearRefusal("a");
    store.clearRefusal("a");
    expect(store.state.refusals.has("a")).toBe(false);
    expect(calls).toBe(2);
  });
});
