// A mission to and from a vehicle, and to and from a file: read the one on board (item 0,
// home, is the vehicle's own and left out), upload one after checking it against that
// vehicle's own rails and home, and save one as a QGroundControl .plan file.
import { ApiError, violationsOf } from "../hub/api";
import type { VehicleSummary } from "../hub/types";
import { checkMission, downloadMission, uploadMission } from "./api";
import { type MissionItem, fullItem } from "./model";
import { writePlan } from "./plan";

/** The mission on board (without home); null when the vehicle sent none. */
export async function missionOnBoard(id: string): Promise<MissionItem[] | null> {
  const result = await downloadMission(id);
  return result.items ? result.items.slice(1).map(fullItem) : null;
}

export interface UploadOutcome {
  /** One line for the status, `<id>: uploaded (...)` when it was. */
  line: string;
  uploaded: boolean;
}

/** One target: checked against its own rails and home first, uploaded only if they pass. */
export async function checkAndUpload(id: string, items: MissionItem[]): Promise<UploadOutcome> {
  const why = (error: unknown): string => {
    const violations = error instanceof ApiError ? violationsOf(error.body) : [];
    if (violations.length) return violations.map((v) => `${v.rule}: ${v.message}`).join("; ");
    return error instanceof Error ? error.message : String(error);
  };
  const refused = (line: string) => ({ line, uploaded: false });
  try {
    const check = await checkMission(id, items);
    if (!check.ok) {
      return refused(`${id}: not uploaded — refused by its rails: ${check.violations.map((v) => `${v.rule}: ${v.message}`).join("; ")}`);
    }
  } catch (error) {
    return refused(`${id}: not uploaded — could not check it (${why(error)})`);
  }
  try {
    const result = await uploadMission(id, items);
    if (result.outcome.status !== "accepted") {
      return refused(`${id}: ${result.outcome.status}${result.outcome.message ? ` — ${result.outcome.message}` : ""}`);
    }
    return { line: `${id}: uploaded (${items.length} items)`, uploaded: true };
  } catch (error) {
    return refused(`${id}: refused — ${why(error)}`);
  }
}

/** Offers the mission as a `.plan` download, with the vehicle's home when known. */
export function savePlanFile(items: readonly MissionItem[], vehicle: VehicleSummary | undefined, name: string): void {
  const state = vehicle?.state;
  const home: [number, number, number] | null =
    state?.home_lat != null && state.home_lon != null ? [state.home_lat, state.home_lon, state.home_alt_msl ?? 0] : null;
  const text = writePlan(items, { home, autopilot: vehicle?.autopilot });
  const link = document.createElement("a");
  link.href = URL.createObjectURL(new Blob([text], { type: "application/json" }));
  link.download = `${name}.plan`;
  link.click();
  window.setTimeout(() => URL.revokeObjectURL(link.href), 10_000);
}
