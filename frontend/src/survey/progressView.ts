// A flying survey's progress in words: its state, the lanes, photos and coverage overall
// and per drone (in the drone's colour), the hand-over offer when a drone dropped out, and
// the abort button; and what the hub's detail of a survey draws on the map.
import { droneColour } from "../map/droneColours";
import { button, el } from "../ui/dom";
import type { SurveyDetail, SurveyProgress } from "./api";
import type { LaneDrawing } from "./layer";

export const ENDED = new Set(["done", "aborted", "failed"]);

export interface ProgressActions {
  /** Null for a user who may not command: no buttons. */
  acceptHandover: (() => void) | null;
  abort: (() => void) | null;
}

/** The progress box's contents for `update`. */
export function progressParts(update: SurveyProgress, actions: ProgressActions): HTMLElement[] {
  const head = el("div", "survey-progress-head", "survey-state");
  head.textContent = `Survey ${update.survey_id}: ${update.state.replace("_", " ")}`;
  const overall = el("div", "survey-overall", "survey-overall");
  overall.dataset.lanesDone = String(update.lanes_done);
  overall.dataset.photos = String(update.photos);
  overall.dataset.covered = String(update.covered_pct);
  const bar = el("progress", "survey-bar");
  bar.max = Math.max(1, update.lanes_total);
  bar.value = update.lanes_done;
  overall.append(
    bar,
    ` ${update.lanes_done}/${update.lanes_total} lanes, ${update.photos} photos, ${update.covered_pct.toFixed(1)} % covered`,
  );
  const list = el("ul", "survey-drone-progress");
  update.drones.forEach((drone, index) => {
    const item = el("li", "");
    item.dataset.vehicleId = drone.vehicle_id;
    item.dataset.state = drone.state;
    item.dataset.lanesDone = String(drone.lanes_done);
    const swatch = el("span", "map-panel-swatch");
    swatch.style.background = droneColour(index);
    const reason = drone.reason ? ` (${drone.reason})` : "";
    item.append(
      swatch,
      `${drone.vehicle_id}: ${drone.state}, ${drone.lanes_done}/${drone.lanes_total} lanes, ${drone.photos} photos${reason}`,
    );
    list.append(item);
  });
  const parts: HTMLElement[] = [head, overall, list];
  if (update.state === "handover_offered" && update.handover_lanes != null) {
    const offer = el("div", "survey-handover", "survey-handover");
    const lost = update.drones.filter((d) => d.state === "dropped").map((d) => d.vehicle_id);
    offer.append(
      `${lost.join(", ") || "A drone"} dropped out: hand ${update.handover_lanes} unflown lanes to the drones still flying? `,
    );
    const onAccept = actions.acceptHandover;
    if (onAccept) {
      const accept = button("survey-accept", "Accept hand-over", "Upload the new missions; each flies on from where it is");
      accept.addEventListener("click", () => onAccept());
      offer.append(accept);
    }
    parts.push(offer);
  }
  const onAbort = actions.abort;
  if (onAbort && !ENDED.has(update.state)) {
    const abort = button("survey-abort", "Abort survey", "Every drone still flying it returns to launch");
    abort.addEventListener("click", () => onAbort());
    parts.push(abort);
  }
  return parts;
}

/** The lanes (flown ones marked done) and photos of a survey's detail, in each drone's colour. */
export function detailDrawing(detail: SurveyDetail): { lanes: LaneDrawing[]; photos: { at: [number, number]; colour: string }[] } {
  const lanes: LaneDrawing[] = [];
  const photos: { at: [number, number]; colour: string }[] = [];
  detail.survey.drones.forEach((drone, index) => {
    const colour = droneColour(index);
    for (const lane of drone.lanes) {
      lanes.push({ vehicleId: drone.vehicle_id, colour, path: [lane.start, lane.end], done: lane.done ?? false });
    }
    for (const at of drone.photos ?? []) photos.push({ at, colour });
  });
  return { lanes, photos };
}
