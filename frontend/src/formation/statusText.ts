// What the formation panel says of a formation, from the hub's own words: its state
// (joining, flying, route_done, stopped) and when its route ends or ended (`route_done_at`),
// never worked out here from `formed_at` and the route's length.
import type { FormationStatus } from "./api";

const STATE_TEXT: Record<FormationStatus["state"], string> = {
  joining: "joining",
  flying: "flying the route",
  route_done: "route done, holding",
  stopped: "stopped",
};

function clock(unixSeconds: number): string {
  return new Date(unixSeconds * 1000).toLocaleTimeString([], { hour12: false });
}

export function formationHeadline(status: FormationStatus): string {
  const leader = status.leader_id ?? "virtual leader";
  const why = status.stopped ? `: ${status.stopped}` : "";
  return `Formation ${status.id} (${leader}): ${STATE_TEXT[status.state]}${why}`;
}

/** "Route done at 12:04:31" once the leader reached the end (or "ends at" while it flies);
 *  empty while the followers join, or when it stopped before the end. */
export function routeEndText(status: FormationStatus): string {
  const at = status.route_done_at;
  if (at === null || at === undefined) return "";
  return `Route ${status.state === "flying" ? "ends" : "done"} at ${clock(at)}`;
}
