// The hub's survey preview in words and colours: the summary (photos, lanes, time, area,
// GSD, altitude, spacing, trigger distance, angle, coverage) and one table row per drone
// (with its battery estimate, and its refusal under it), and the lanes to draw.
import { droneColour } from "../map/droneColours";
import { el } from "../ui/dom";
import type { SurveyPreview } from "./api";
import type { LaneDrawing } from "./layer";

export function formatDuration(seconds: number): string {
  const s = Math.round(seconds);
  return `${Math.floor(s / 60)}:${String(s % 60).padStart(2, "0")}`;
}

function formatArea(m2: number): string {
  return m2 >= 10_000 ? `${(m2 / 10_000).toFixed(2)} ha` : `${Math.round(m2)} m²`;
}

/** The per-drone table, its body (`survey-parts`) filled by `renderPreview`. */
export function partsTable(): [HTMLTableElement, HTMLTableSectionElement] {
  const table = el("table", "survey-parts");
  const headRow = table.createTHead().insertRow();
  for (const text of ["Drone", "Lanes", "Photos", "Time", "Battery"]) {
    const cell = el("th", "");
    cell.textContent = text;
    headRow.append(cell);
  }
  const parts = table.createTBody();
  parts.dataset.field = "survey-parts";
  return [table, parts];
}

/** Fills the summary and the parts' table; returns the lanes, each in its drone's colour. */
export function renderPreview(summary: HTMLElement, parts: HTMLTableSectionElement, preview: SurveyPreview): LaneDrawing[] {
  const slowest = Math.max(...preview.parts.map((part) => part.total_s));
  const rows: [string, string, string][] = [
    ["photos", "Photos", String(preview.photo_count)],
    ["lanes", "Lanes", String(preview.lanes)],
    ["time", "Time", formatDuration(slowest)],
    ["area", "Area", formatArea(preview.area_m2)],
    ["gsd", "GSD", preview.gsd_cm == null ? "unknown (manual camera)" : `${preview.gsd_cm.toFixed(2)} cm/px`],
    ["altitude", "Altitude", `${preview.altitude_m.toFixed(1)} m`],
    ["spacing", "Lane spacing", `${preview.lane_spacing_m.toFixed(1)} m`],
    ["trigger", "Trigger every", `${preview.trigger_distance_m.toFixed(1)} m`],
    ["angle", "Angle", `${preview.angle_deg.toFixed(0)}°`],
    ["coverage", "Coverage", `${preview.coverage_pct.toFixed(1)} %`],
  ];
  for (const [field, label, value] of rows) {
    const term = el("dt", "");
    term.textContent = label;
    const data = el("dd", "", `survey-${field}`);
    data.textContent = value;
    summary.append(term, data);
  }
  const lanes: LaneDrawing[] = [];
  preview.parts.forEach((part, index) => {
    const colour = droneColour(index);
    for (const path of part.lane_paths) {
      lanes.push({ vehicleId: part.vehicle_id, colour, path: path as [number, number][], done: false });
    }
    const row = parts.insertRow();
    row.dataset.vehicleId = part.vehicle_id;
    row.classList.toggle("refused", !part.check.ok);
    const estimate = part.check.estimate;
    const battery = estimate
      ? `${estimate.required_pct.toFixed(0)} %${estimate.available_pct == null ? "" : ` of ${estimate.available_pct.toFixed(0)} %`}`
      : "unknown";
    const cells = [part.vehicle_id, String(part.lanes), String(part.photo_count), formatDuration(part.total_s), battery];
    cells.forEach((text, column) => {
      const cell = row.insertCell();
      cell.textContent = text;
      if (column === 0) {
        const swatch = el("span", "map-panel-swatch");
        swatch.style.background = colour;
        cell.prepend(swatch);
      }
    });
    row.cells[3].title = `transit ${formatDuration(part.transit_s)}, lanes ${formatDuration(part.survey_s)}, home ${formatDuration(part.home_s)}`;
    if (!part.check.ok) {
      const why = parts.insertRow();
      why.className = "survey-refusal";
      why.dataset.vehicleId = part.vehicle_id;
      const cell = why.insertCell();
      cell.colSpan = 5;
      cell.dataset.field = "refusal";
      cell.textContent = `${part.vehicle_id}: ${part.check.violations.map((v) => v.message).join("; ")}`;
    }
  });
  return lanes;
}
