import { describe, expect, it } from "vitest";

import type { FormationStatus } from "./api";
import { formationHeadline, routeEndText } from "./statusText";

function status(over: Partial<FormationStatus>): FormationStatus {
  return {
    id: "formation-1",
    leader_id: "sim_1",
    slots: {},
    started_at: 100,
    formed_at: 110,
    route_duration_s: 60,
    state: "flying",
    route_done_at: 170,
    controller: "leader_follower",
    tracking: {},
    stopped: null,
    ...over,
  };
}

const clock = (t: number) => new Date(t * 1000).toLocaleTimeString([], { hour12: false });

describe("the formation's status line", () => {
  it("says when the route ends, and once done when it was done, from the hub's time", () => {
    expect(routeEndText(status({}))).toBe(`Route ends at ${clock(170)}`);
    expect(routeEndText(status({ state: "route_done" }))).toBe(`Route done at ${clock(170)}`);
    expect(formationHeadline(status({ state: "route_done" }))).toBe("Formation formation-1 (sim_1): route done, holding");
  });

  it("says nothing of the end while joining or when stopped short of it", () => {
    expect(routeEndText(status({ state: "joining", formed_at: null, route_done_at: null }))).toBe("");
    const stopped = status({ state: "stopped", route_done_at: null, stopped: "stopped by the operator" });
    expect(routeEndText(stopped)).toBe("");
    expect(formationHeadline(stopped)).toBe("Formation formation-1 (sim_1): stopped: stopped by the operator");
  });
});
