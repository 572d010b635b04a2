// The survey panel: draw the area (and its holes) on the map or open a file, choose the
// camera, GSD or altitude, overlaps, angle, speed and drones; the hub's preview (lanes per
// drone in its own colour, photos, time, area, battery per drone, each refusal named)
// follows every change. Launch creates the survey and starts it; progress then comes from
// the live feed's `survey` messages, the flown lanes fade, the photos appear as dots, and a
// hand-over offer is one button.
import * as L from "leaflet";
import { FoldingPanel, MapClicks } from "../map/foldingPanel";
import { errorText } from "../hub/api";
import { button, el, say } from "../ui/dom";
import type { SurveyUpdate } from "../generated/protocol";
import type { VehicleSummary } from "../hub/types";
import type { DashboardStore } from "../store/dashboardStore";
import { changedValues } from "../store/store";
import { DroneChooser } from "./droneChooser";
import { SurveyForm } from "./surveyForm";
import {
  type GeoJsonPolygon,
  type SurveyDetail,
  type SurveyPreview,
  type SurveyProgress,
  type SurveyRequest,
  abortSurvey,
  acceptHandover,
  createSurvey,
  getMosaic,
  getSurvey,
  importArea,
  previewSurvey,
  startSurvey,
} from "./api";
import { SurveyLayer } from "./layer";
import { partsTable, renderPreview } from "./previewView";
import { ENDED, detailDrawing, progressParts } from "./progressView";

const PREVIEW_DELAY_MS = 400;
/** The flown lanes, photos and mosaic are re-read at most this often while a survey flies. */
const DETAIL_EVERY_MS = 1000;

function ringToGeo(ring: readonly L.LatLng[]): number[][] {
  const coords = ring.map((p) => [p.lng, p.lat]);
  return [...coords, coords[0]];
}

export class SurveyPanel {
  readonly element: HTMLElement;
  private readonly panel: FoldingPanel;
  private readonly clicks: MapClicks;
  private readonly layer: SurveyLayer;
  /** Closed rings: the outline, then holes. */
  private rings: L.LatLng[][] = [];
  /** The ring being drawn, or null when not drawing. */
  private drawing: L.LatLng[] | null = null;
  private preview: SurveyPreview | null = null;
  private previewTimer: number | undefined;
  private previewAbort: AbortController | null = null;
  private surveyId: string | null = null;
  private progress: SurveyProgress | null = null;
  private detailAt = 0;
  private detailBusy = false;
  private destroyed = false;

  private readonly body: HTMLElement;
  private readonly drawButton: HTMLButtonElement;
  private readonly closeButton: HTMLButtonElement;
  private readonly holeButton: HTMLButtonElement;
  private readonly form: SurveyForm;
  private readonly drones = new DroneChooser(() => {
    void this.form.chooseFor(this.drones.ids).catch(() => undefined); // the presets are read again at the next choice
    this.schedulePreview();
  });
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
    this.layer = new SurveyLayer(map, store);
    this.panel = new FoldingPanel(map, "survey", "Survey", "Plan and fly an area survey");
    this.element = this.panel.element;
    this.body = this.panel.body;
    const clickTool = { label: "Drawing survey area", owner: this.element, onEnd: () => this.endRing() };
    this.clicks = new MapClicks(map, (at) => (this.drawing?.push(at), this.renderArea()), clickTool);

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
    this.form = new SurveyForm(() => this.schedulePreview());
    this.form.loadCameras().then(
      () => this.rings.length > 0 && this.schedulePreview(), // an area drawn meanwhile
      (error: unknown) => this.say(`Camera presets: ${errorText(error)}`, true),
    );

    // -- the preview and the launch
    this.summary = el("dl", "survey-summary", "survey-summary");
    let table: HTMLTableElement;
    [table, this.parts] = partsTable();
    this.launchButton = button("survey-launch", "Launch survey", "Create the survey, upload every part and start");
    this.launchButton.disabled = true;
    this.launchButton.addEventListener("click", () => void this.launch());
    this.status = el("div", "mission-status", "survey-status");
    this.status.setAttribute("role", "status");
    this.progressBox = el("div", "survey-progress", "survey-progress");
    this.progressBox.hidden = true;

    const hint = el("p", "mission-hint");
    hint.textContent = "Draw: click the map for each corner, then click the first corner or Close ring.";
    this.planning = el("div", "survey-planning");
    this.planning.append(areaTools, hint, this.form.element, this.drones.element, this.summary, table, this.launchButton);
    this.planning.hidden = !canCommand;
    // The flight's progress on top: while a survey flies the planning form folds away,
    // so the hand-over prompt is never scrolled out of sight.
    this.body.append(this.progressBox, this.status, this.planning, this.fileInput);
    this.renderArea();
  }

  update(vehicles: Iterable<VehicleSummary>): void {
    this.drones.update(vehicles);
  }
  remove(id: string): void {
    this.drones.remove(id);
  }

  /** A `survey` message from the live feed. */
  private onSurvey(update: SurveyUpdate): void {
    // A dashboard opened mid-survey follows the one that is flying.
    if (!this.surveyIsLive() && !ENDED.has(update.state)) this.surveyId = update.survey_id;
    if (update.survey_id !== this.surveyId) return;
    this.progress = update;
    this.renderProgress();
    if (Date.now() - this.detailAt >= DETAIL_EVERY_MS || ENDED.has(update.state)) void this.refreshDetail();
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

  /** Ended from outside (Esc, Done, a fold): three corners or more close the ring, fewer go. */
  private endRing(): void {
    if ((this.drawing?.length ?? 0) >= 3) return this.closeRing();
    this.drawing = null;
    this.renderArea();
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
      this.form.applyFile(fields, file.name);
      this.renderArea();
      this.map.fitBounds(L.latLngBounds(this.rings[0]), { padding: [40, 40] });
      this.say(`Opened ${file.name}.`);
      this.schedulePreview();
    } catch (error) {
      this.say(`Could not open ${file.name}: ${(error as Error).message}`, true);
    }
  }

  // ------------------------------------------------------------------ the preview

  private request(): SurveyRequest | null {
    const area = this.areaGeoJson();
    const vehicleIds = this.drones.ids;
    if (!area || vehicleIds.length === 0) return null;
    return {
      area,
      ...this.form.settings(),
      // Ids in the fleet list's order, so the colours follow the checkboxes.
      vehicle_ids: vehicleIds,
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
    const lanes = renderPreview(this.summary, this.parts, preview);
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
    const { lanes, photos } = detailDrawing(detail);
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
    const act = (action: (id: string) => Promise<SurveyDetail>, done: string) =>
      this.canCommand ? () => void this.act(action, done) : null;
    this.progressBox.append(
      ...progressParts(update, {
        acceptHandover: act(acceptHandover, "Hand-over accepted."),
        abort: act(abortSurvey, "Survey aborted: the drones return to launch."),
      }),
    );
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
