// The survey panel: draw the area (and its holes) on the map or open a file, choose the
// camera, GSD or altitude, overlaps, angle, speed and drones; the hub's preview (lanes per
// drone in its own colour, photos, time, area, battery per drone, each refusal named)
// follows every change. Launch creates the survey and starts it; progress then comes from
// the live feed's `survey` messages, the flown lanes fade, the photos appear as dots, and a
// hand-over offer is one button.
import * as L from "leaflet";
import { droneColour } from "../map/droneColours";
import { FoldingPanel, MapClicks } from "../map/foldingPanel";
import { errorText } from "../hub/api";
import { button, el, numberField, say } from "../ui/dom";
import type { SurveyUpdate } from "../generated/protocol";
import type { VehicleSummary } from "../hub/types";
import type { DashboardStore } from "../store/dashboardStore";
import { changedValues } from "../store/store";
import {
  type GeoJsonPolygon,
  type SurveyDetail,
  type SurveyPreview,
  type SurveyProgress,
  type SurveyRequest,
  abortSurvey,
  acceptHandover,
  cameraPresets,
  createSurvey,
  getMosaic,
  getSurvey,
  importArea,
  previewSurvey,
  startSurvey,
} from "./api";
import { type LaneDrawing, SurveyLayer } from "./layer";

const PREVIEW_DELAY_MS = 400;
/** The flown lanes, photos and mosaic are re-read at most this often while a survey flies. */
const DETAIL_EVERY_MS = 1000;
const ENDED = new Set(["done", "aborted", "failed"]);

export function formatDuration(seconds: number): string {
  const s = Math.round(seconds);
  return `${Math.floor(s / 60)}:${String(s % 60).padStart(2, "0")}`;
}

function formatArea(m2: number): string {
  return m2 >= 10_000 ? `${(m2 / 10_000).toFixed(2)} ha` : `${Math.round(m2)} m²`;
}

function ringToGeo(ring: readonly L.LatLng[]): number[][] {
  const coords = ring.map((p) => [p.lng, p.lat]);
  return [...coords, coords[0]];
}

export class SurveyPanel {
  readonly element: HTMLElement;
  private readonly panel: FoldingPanel;
  private readonly clicks: MapClicks;
  private readonly layer: SurveyLayer;
  private readonly vehicles = new Map<string, VehicleSummary>();
  private readonly chosen = new Set<string>();
  /** Closed rings: the outline, then holes. */
  private rings: L.LatLng[][] = [];
  /** The ring being drawn, or null when not drawing. */
  private drawing: L.LatLng[] | null = null;
  private preview: SurveyPreview | null = null;
  private previewTimer: number | undefined;
  private previewAbort: AbortController | null = null;
  private surveyId: string | null = null;
  /** A camera's figures from an opened file (a QGC Survey), offered as "From file". */
  private fileCamera: SurveyRequest["camera"] | null = null;
  private progress: SurveyProgress | null = null;
  private detailAt = 0;
  private detailBusy = false;
  private destroyed = false;

  private readonly body: HTMLElement;
  private readonly drawButton: HTMLButtonElement;
  private readonly closeButton: HTMLButtonElement;
  private readonly holeButton: HTMLButtonElement;
  private readonly camera: HTMLSelectElement;
  private readonly heightKind: HTMLSelectElement;
  private readonly height: HTMLInputElement;
  private readonly side: HTMLInputElement;
  private readonly front: HTMLInputElement;
  private readonly angle: HTMLInputElement;
  private readonly speed: HTMLInputElement;
  private readonly drones: HTMLElement;
  private readonly summary: HTMLElement;
  private readonly parts: HTMLTableSectionElement;
  private readonly status: HTMLElement;
  private readonly launchButton: HTMLButtonElement;
  private readonly progressBox: HTMLElement;
  private readonly planning: HTMLElement;
  private readonly fileInput: HTMLInputElement;

  constructor(
    private readonly map: L.Map,
    private readonly canCommand: boolean,
    store: DashboardStore,
  ) {
    store.followFleet(this);
    store.subscribe(
      (state) => state.surveys,
      (now, before) => {
        for (const update of changedValues(now, before)) this.onSurvey(update);
      },
    );
    this.layer = new SurveyLayer(map);
    this.panel = new FoldingPanel(map, "survey", "Survey", "Plan and fly an area survey");
    this.element = this.panel.element;
    this.body = this.panel.body;
    this.clicks = new MapClicks(map, (at) => {
      this.drawing?.push(at);
      this.renderArea();
    });

    // -- the area
    this.drawButton = button("survey-draw", "Draw area", "Click the map to place the area's corners");
    this.drawButton.addEventListener("click", () => this.startRing(true));
    this.holeButton = button("survey-hole", "Add hole", "Draw a no-fly area inside the outline");
    this.holeButton.addEventListener("click", () => this.startRing(false));
    this.closeButton = button("survey-close", "Close ring", "Close the ring being drawn (or click its first corner)");
    this.closeButton.addEventListener("click", () => this.closeRing());
    const clear = button("survey-clear", "Clear", "Remove the area and the plan");
    clear.addEventListener("click", () => this.clearArea());
    const open = button("survey-open", "Open file", "An area from a QGC .plan, KML or GeoJSON file");
    this.fileInput = el("input", "mission-file", "survey-file");
    this.fileInput.type = "file";
    this.fileInput.accept = ".plan,.kml,.geojson,.json,application/json,application/vnd.google-earth.kml+xml";
    this.fileInput.hidden = true;
    open.addEventListener("click", () => this.fileInput.click());
    this.fileInput.addEventListener("change", () => void this.openFile());
    const areaTools = el("div", "mission-toolbar");
    areaTools.append(this.drawButton, this.holeButton, this.closeButton, clear, open);

    // -- the camera and the flight
    this.camera = el("select", "survey-select", "survey-camera");
    void this.loadCameras();
    const cameraLabel = el("label", "map-panel-field");
    cameraLabel.append("Camera ", this.camera);
    this.heightKind = el("select", "survey-select", "survey-height-kind");
    this.heightKind.append(new Option("Altitude (m)", "altitude"), new Option("GSD (cm/px)", "gsd"));
    this.height = el("input", "mission-number", "survey-height");
    this.height.type = "number";
    this.height.step = "any";
    this.height.value = "40";
    this.heightKind.addEventListener("change", () => {
      this.height.value = this.heightKind.value === "gsd" ? "1.0" : "40";
    });
    const heightLabel = el("label", "map-panel-field");
    heightLabel.append(this.heightKind, this.height);
    let wrap: HTMLLabelElement;
    const fields = el("div", "map-panel-fields");
    fields.append(cameraLabel, heightLabel);
    [wrap, this.side] = numberField("survey-side", "Side overlap %", "70", "Between neighbouring lanes");
    fields.append(wrap);
    [wrap, this.front] = numberField("survey-front", "Front overlap %", "80", "Between photos along a lane");
    fields.append(wrap);
    [wrap, this.angle] = numberField("survey-angle", "Angle °", "", "Lane heading; empty chooses the fastest");
    this.angle.placeholder = "auto";
    fields.append(wrap);
    [wrap, this.speed] = numberField("survey-speed", "Speed m/s", "8", "Ground speed along the lanes");
    fields.append(wrap);
    this.drones = el("div", "survey-drones", "survey-drones");

    // -- the preview and the launch
    this.summary = el("dl", "survey-summary", "survey-summary");
    const table = el("table", "survey-parts");
    const headRow = table.createTHead().insertRow();
    for (const text of ["Drone", "Lanes", "Photos", "Time", "Battery"]) {
      const cell = document.createElement("th");
      cell.textContent = text;
      headRow.append(cell);
    }
    this.parts = table.createTBody();
    this.parts.dataset.field = "survey-parts";
    this.launchButton = button("survey-launch", "Launch survey", "Create the survey, upload every part and start");
    this.launchButton.disabled = true;
    this.launchButton.addEventListener("click", () => void this.launch());
    this.status = el("div", "mission-status", "survey-status");
    this.status.setAttribute("role", "status");
    this.progressBox = el("div", "survey-progress", "survey-progress");
    this.progressBox.hidden = true;

    // Every keystroke re-plans (debounced): the preview follows the inputs as they change.
    for (const input of [this.camera, this.heightKind]) input.addEventListener("change", () => this.schedulePreview());
    for (const input of [this.height, this.side, this.front, this.angle, this.speed]) {
      input.addEventListener("input", () => this.schedulePreview());
    }
    const hint = el("p", "mission-hint");
    hint.textContent = "Draw: click the map for each corner, then click the first corner or Close ring.";
    this.planning = el("div", "survey-planning");
    this.planning.append(areaTools, hint, fields, this.drones, this.summary, table, this.launchButton);
    this.planning.hidden = !canCommand;
    // The flight's progress on top: while a survey flies the planning form folds away,
    // so the hand-over prompt is never scrolled out of sight.
    this.body.append(this.progressBox, this.status, this.planning, this.fileInput);
    this.renderArea();
  }

  update(vehicles: Iterable<VehicleSummary>): void {
    let added = false;
    for (const vehicle of vehicles) {
      if (!this.vehicles.has(vehicle.id)) added = true;
      this.vehicles.set(vehicle.id, vehicle);
    }
    if (added) this.renderDrones();
  }

  remove(id: string): void {
    this.vehicles.delete(id);
    this.chosen.delete(id);
    this.renderDrones();
  }

  /** A `survey` message from the live feed. */
  private onSurvey(update: SurveyUpdate): void {
    // A dashboard opened mid-survey follows the one that is flying.
    if (!this.surveyIsLive() && !ENDED.has(update.state)) this.surveyId = update.survey_id;
    if (update.survey_id !== this.surveyId) return;
    this.progress = update;
    this.renderProgress();
    const now = Date.now();
    if (now - this.detailAt >= DETAIL_EVERY_MS || ENDED.has(update.state)) void this.refreshDetail();
  }

  destroy(): void {
    this.destroyed = true;
    window.clearTimeout(this.previewTimer);
    this.previewAbort?.abort();
    this.clicks.destroy();
    this.panel.remove();
    this.layer.destroy();
  }

  // ------------------------------------------------------------------ the area

  private startRing(outline: boolean): void {
    if (outline) {
      this.rings = [];
      this.preview = null;
      this.layer.clearPlan();
    } else if (this.rings.length === 0) {
      this.say("Draw the outline first.");
      return;
    }
    this.drawing = [];
    this.clicks.start();
    this.renderArea();
  }

  private closeRing(): void {
    if (!this.drawing) return;
    if (this.drawing.length < 3) {
      this.say("A ring needs at least three corners.");
      return;
    }
    this.rings.push(this.drawing);
    this.drawing = null;
    this.clicks.stop();
    this.renderArea();
    this.schedulePreview();
  }

  private clearArea(): void {
    this.rings = [];
    this.drawing = null;
    this.preview = null;
    this.clicks.stop();
    this.layer.clearPlan();
    this.renderArea();
    this.renderPreview();
  }

  private renderArea(): void {
    this.layer.drawArea(this.rings, this.drawing, () => this.closeRing());
    this.drawButton.classList.toggle("active", this.drawing !== null && this.rings.length === 0);
    this.closeButton.disabled = this.drawing === null;
    this.holeButton.disabled = this.rings.length === 0 || this.drawing !== null;
    this.element.dataset.rings = String(this.rings.length);
  }

  private areaGeoJson(): GeoJsonPolygon | null {
    if (this.rings.length === 0) return null;
    return { type: "Polygon", coordinates: this.rings.map(ringToGeo) };
  }

  private async openFile(): Promise<void> {
    const file = this.fileInput.files?.[0];
    this.fileInput.value = "";
    if (!file) return;
    const name = file.name.toLowerCase();
    const format = name.endsWith(".plan") ? "plan" : name.endsWith(".kml") ? "kml" : "geojson";
    try {
      const fields = await importArea(format, await file.text());
      if (this.destroyed) return;
      const area = fields.area;
      if (!area) throw new Error("the file has no area");
      this.rings = area.coordinates.map((ring) => ring.slice(0, -1).map(([lon, lat]) => L.latLng(lat, lon)));
      this.drawing = null;
      if (typeof fields.camera === "string") this.camera.value = fields.camera;
      else if (fields.camera) {
        this.fileCamera = fields.camera;
        this.camera.querySelector('option[value="file"]')?.remove();
        // A QGC manual camera has no figures: its spacing and trigger distance are the plan.
        const manual = "lane_spacing_m" in fields.camera ? fields.camera : null;
        const label = manual
          ? `From ${file.name} (manual: lanes ${manual.lane_spacing_m} m apart, a photo every ${manual.trigger_distance_m} m)`
          : `From ${file.name}`;
        this.camera.append(new Option(label, "file"));
        this.camera.value = "file";
      }
      if (fields.altitude_m != null) [this.heightKind.value, this.height.value] = ["altitude", String(fields.altitude_m)];
      else if (fields.gsd_cm != null) [this.heightKind.value, this.height.value] = ["gsd", String(fields.gsd_cm)];
      if (fields.side_overlap_pct != null) this.side.value = String(fields.side_overlap_pct);
      if (fields.front_overlap_pct != null) this.front.value = String(fields.front_overlap_pct);
      if (fields.angle_deg != null) this.angle.value = String(fields.angle_deg);
      this.renderArea();
      this.map.fitBounds(L.latLngBounds(this.rings[0]), { padding: [40, 40] });
      this.say(`Opened ${file.name}.`);
      this.schedulePreview();
    } catch (error) {
      this.say(`Could not open ${file.name}: ${(error as Error).message}`, true);
    }
  }

  // ------------------------------------------------------------------ the drones

  private renderDrones(): void {
    const ids = [...this.vehicles.keys()].sort();
    this.drones.replaceChildren(
      el("span", "survey-drones-title"),
      ...ids.map((id) => {
        const label = el("label", "survey-drone");
        label.dataset.vehicleId = id;
        const box = el("input", "survey-drone-box");
        box.type = "checkbox";
        box.checked = this.chosen.has(id);
        box.addEventListener("change", () => {
          if (box.checked) this.chosen.add(id);
          else this.chosen.delete(id);
          this.schedulePreview();
        });
        label.append(box, ` ${id}`);
        return label;
      }),
    );
    this.drones.firstElementChild!.textContent = "Drones:";
  }

  // ------------------------------------------------------------------ the preview

  private request(): SurveyRequest | null {
    const area = this.areaGeoJson();
    if (!area || this.chosen.size === 0) return null;
    const number = (input: HTMLInputElement) => Number.parseFloat(input.value);
    const height = number(this.height);
    const angle = this.angle.value.trim() === "" ? null : number(this.angle);
    return {
      area,
      camera: this.camera.value === "file" && this.fileCamera ? this.fileCamera : this.camera.value,
      altitude_m: this.heightKind.value === "altitude" ? height : null,
      gsd_cm: this.heightKind.value === "gsd" ? height : null,
      side_overlap_pct: number(this.side),
      front_overlap_pct: number(this.front),
      angle_deg: angle,
      speed_ms: number(this.speed),
      // Ids in the fleet list's order, so the colours follow the checkboxes.
      vehicle_ids: [...this.vehicles.keys()].sort().filter((id) => this.chosen.has(id)),
    } as SurveyRequest;
  }

  private schedulePreview(): void {
    window.clearTimeout(this.previewTimer);
    this.previewAbort?.abort();
    this.launchButton.disabled = true;
    if (!this.canCommand || this.surveyIsLive()) return;
    const body = this.request();
    if (!body) {
      this.preview = null;
      this.renderPreview();
      this.say(this.rings.length === 0 ? "Draw the area first." : "Choose at least one drone.");
      return;
    }
    this.summary.dataset.state = "pending";
    this.previewTimer = window.setTimeout(() => void this.runPreview(body), PREVIEW_DELAY_MS);
  }

  /** The hub's presets, with their figures in each option's title. */
  private async loadCameras(): Promise<void> {
    try {
      for (const camera of await cameraPresets()) {
        const option = new Option(camera.name, camera.id);
        option.title =
          `${camera.sensor_width_mm} x ${camera.sensor_height_mm} mm sensor, ` +
          `${camera.image_width_px} x ${camera.image_height_px} px, ${camera.focal_length_mm} mm`;
        this.camera.append(option);
      }
      if (this.rings.length > 0) this.schedulePreview(); // an area drawn meanwhile
    } catch (error) {
      this.say(`Camera presets: ${errorText(error)}`, true);
    }
  }

  private async runPreview(body: SurveyRequest): Promise<void> {
    const abort = new AbortController();
    this.previewAbort = abort;
    try {
      const preview = await previewSurvey(body, abort.signal);
      if (abort.signal.aborted || this.destroyed) return;
      this.preview = preview;
      this.say(preview.ok ? "Every part passes the safety rails." : "Some parts are refused: see below.", !preview.ok);
    } catch (error) {
      if (abort.signal.aborted || this.destroyed) return;
      this.preview = null;
      this.say(errorText(error), true);
    }
    this.renderPreview();
  }

  private renderPreview(): void {
    const preview = this.preview;
    this.summary.replaceChildren();
    this.parts.replaceChildren();
    this.summary.dataset.state = preview ? (preview.ok ? "ok" : "refused") : "none";
    this.launchButton.disabled = !preview?.ok || this.surveyIsLive();
    if (!preview) {
      if (!this.surveyIsLive()) this.layer.clearPlan();
      return;
    }
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
      this.summary.append(term, data);
    }
    const lanes: LaneDrawing[] = [];
    preview.parts.forEach((part, index) => {
      const colour = droneColour(index);
      for (const path of part.lane_paths) {
        lanes.push({ vehicleId: part.vehicle_id, colour, path: path as [number, number][], done: false });
      }
      const row = this.parts.insertRow();
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
        const why = this.parts.insertRow();
        why.className = "survey-refusal";
        why.dataset.vehicleId = part.vehicle_id;
        const cell = why.insertCell();
        cell.colSpan = 5;
        cell.dataset.field = "refusal";
        cell.textContent = `${part.vehicle_id}: ${part.check.violations.map((v) => v.message).join("; ")}`;
      }
    });
    this.layer.drawLanes(lanes);
  }

  // ------------------------------------------------------------------ the flight

  private surveyIsLive(): boolean {
    return this.surveyId !== null && (this.progress === null || !ENDED.has(this.progress.state));
  }

  private async launch(): Promise<void> {
    const body = this.request();
    if (!body) return;
    this.launchButton.disabled = true;
    this.say("Creating the survey…");
    try {
      const created = await createSurvey(body);
      this.surveyId = created.survey.id;
      this.progress = created.progress;
      this.say("Uploading every part and starting…");
      const started = await startSurvey(created.survey.id);
      this.showDetail(started);
      this.say(`Survey ${started.survey.id} started.`);
    } catch (error) {
      this.say(errorText(error), true);
      if (this.progress === null || this.progress.state === "planned") {
        this.surveyId = null;
        this.progress = null;
      }
      this.launchButton.disabled = !this.preview?.ok;
    }
    this.renderProgress();
  }

  private async refreshDetail(): Promise<void> {
    const id = this.surveyId;
    if (!id || this.detailBusy) return;
    this.detailBusy = true;
    this.detailAt = Date.now();
    try {
      const [detail, mosaic] = await Promise.all([getSurvey(id), getMosaic(id)]);
      if (!this.destroyed && id === this.surveyId) {
        this.showDetail(detail);
        if (mosaic) this.layer.showMosaic(mosaic);
      }
    } catch {
      // The next progress message tries again.
    } finally {
      this.detailBusy = false;
    }
  }

  private showDetail(detail: SurveyDetail): void {
    this.progress = detail.progress;
    const lanes: LaneDrawing[] = [];
    const photos: { at: [number, number]; colour: string }[] = [];
    detail.survey.drones.forEach((drone, index) => {
      const colour = droneColour(index);
      for (const lane of drone.lanes) {
        lanes.push({ vehicleId: drone.vehicle_id, colour, path: [lane.start, lane.end], done: lane.done ?? false });
      }
      for (const at of drone.photos ?? []) photos.push({ at, colour });
    });
    this.layer.drawLanes(lanes);
    this.layer.drawPhotos(photos);
    this.renderProgress();
  }

  private renderProgress(): void {
    const update = this.progress;
    this.progressBox.hidden = update === null;
    this.progressBox.replaceChildren();
    this.planning.hidden = !this.canCommand || this.surveyIsLive();
    if (!update) return;
    if (ENDED.has(update.state)) this.launchButton.disabled = !this.preview?.ok;
    this.progressBox.dataset.state = update.state;
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
    this.progressBox.append(head, overall, list);
    if (update.state === "handover_offered" && update.handover_lanes != null) {
      const offer = el("div", "survey-handover", "survey-handover");
      const lost = update.drones.filter((d) => d.state === "dropped").map((d) => d.vehicle_id);
      offer.append(
        `${lost.join(", ") || "A drone"} dropped out: hand ${update.handover_lanes} unflown lanes to the drones still flying? `,
      );
      if (this.canCommand) {
        const accept = button("survey-accept", "Accept hand-over", "Upload the new missions; each flies on from where it is");
        accept.addEventListener("click", () => void this.act(acceptHandover, "Hand-over accepted."));
        offer.append(accept);
      }
      this.progressBox.append(offer);
    }
    if (this.canCommand && !ENDED.has(update.state)) {
      const abort = button("survey-abort", "Abort survey", "Every drone still flying it returns to launch");
      abort.addEventListener("click", () => void this.act(abortSurvey, "Survey aborted: the drones return to launch."));
      this.progressBox.append(abort);
    }
  }

  private async act(action: (id: string) => Promise<SurveyDetail>, done: string): Promise<void> {
    if (!this.surveyId) return;
    try {
      this.showDetail(await action(this.surveyId));
      this.say(done);
    } catch (error) {
      this.say(errorText(error), true);
    }
  }

  private say(text: string, bad = false): void {
    say(this.status, text, bad);
  }
}
