// The survey's flight settings: the camera (a hub preset, or one an opened file names),
// altitude or GSD, the overlaps, the lane angle and the speed. Every change calls
// `onChange` (the panel re-plans, debounced). The hub's presets start with the cameras the
// fleet's drones carry; choosing drones that all carry one chooses it, unless the operator
// has chosen a camera by hand (the hub's preview then says which drone's camera differs).
import { el, element, numberField } from "../ui/dom";
import { type CameraPreset, type SurveyRequest, cameraPresets } from "./api";

export type SurveySettings = Omit<SurveyRequest, "area" | "vehicle_ids">;

export class SurveyForm {
  readonly element: HTMLElement;
  private readonly camera: HTMLSelectElement;
  private readonly heightKind: HTMLSelectElement;
  private readonly height: HTMLInputElement;
  private readonly side: HTMLInputElement;
  private readonly front: HTMLInputElement;
  private readonly angle: HTMLInputElement;
  private readonly speed: HTMLInputElement;
  /** A camera's figures from an opened file (a QGC Survey), offered as "From file". */
  private fileCamera: SurveyRequest["camera"] | null = null;
  /** The hub's presets as last read: the fleet's cameras (with their drones) first. */
  private presets: CameraPreset[] = [];
  /** The operator chose the camera: the drones' own no longer replaces it. */
  private chosenByHand = false;

  constructor(private readonly onChange: () => void) {
    this.camera = el("select", "survey-select", "survey-camera");
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
    this.element = el("div", "map-panel-fields");
    this.element.append(cameraLabel, heightLabel);
    [wrap, this.side] = numberField("survey-side", "Side overlap %", "70", "Between neighbouring lanes");
    this.element.append(wrap);
    [wrap, this.front] = numberField("survey-front", "Front overlap %", "80", "Between photos along a lane");
    this.element.append(wrap);
    [wrap, this.angle] = numberField("survey-angle", "Angle °", "", "Lane heading; empty chooses the fastest");
    this.angle.placeholder = "auto";
    this.element.append(wrap);
    [wrap, this.speed] = numberField("survey-speed", "Speed m/s", "8", "Ground speed along the lanes");
    this.element.append(wrap);
    // Every keystroke re-plans (debounced): the preview follows the inputs as they change.
    for (const input of [this.camera, this.heightKind]) input.addEventListener("change", onChange);
    this.camera.addEventListener("change", () => (this.chosenByHand = true));
    for (const input of [this.height, this.side, this.front, this.angle, this.speed]) {
      input.addEventListener("input", onChange);
    }
  }

  /** Offers the hub's presets, with their figures in each option's title: the fleet's
   *  cameras in a group of their own, then the catalogue's. Keeps the choice made. */
  async loadCameras(): Promise<void> {
    this.presets = await cameraPresets();
    const chosen = this.camera.value;
    const fromFile = this.camera.querySelector('option[value="file"]');
    const group = (label: string, presets: CameraPreset[]) =>
      element("optgroup", { label }, ...presets.map((camera) => this.option(camera)));
    const fleet = this.presets.filter((camera) => (camera.vehicle_ids ?? []).length > 0);
    const catalogue = this.presets.filter((camera) => (camera.vehicle_ids ?? []).length === 0);
    this.camera.replaceChildren(
      ...(fleet.length > 0 ? [group("The fleet's cameras", fleet)] : []),
      group("Catalogue", catalogue),
      ...(fromFile ? [fromFile] : []),
    );
    if (chosen && [...this.camera.options].some((option) => option.value === chosen)) this.camera.value = chosen;
  }

  private option(camera: CameraPreset): HTMLOptionElement {
    // A fleet camera's name ends with its figures, which the title has: the list keeps to
    // the width the panel's two columns give it.
    const option = new Option(camera.name.replace(/ \(.*\)$/, ""), camera.id);
    option.title =
      `${camera.sensor_width_mm} x ${camera.sensor_height_mm} mm sensor, ` +
      `${camera.image_width_px} x ${camera.image_height_px} px, ${camera.focal_length_mm} mm`;
    return option;
  }

  /** The drones chosen changed: when they all carry one camera, it becomes the survey's
   *  (a drone the presets do not list yet may have connected since: they are read again). */
  async chooseFor(vehicleIds: readonly string[]): Promise<void> {
    const carries = (camera: CameraPreset, id: string) => (camera.vehicle_ids ?? []).includes(id);
    if (vehicleIds.some((id) => !this.presets.some((camera) => carries(camera, id)))) await this.loadCameras();
    if (this.chosenByHand || this.camera.value === "file" || vehicleIds.length === 0) return;
    const shared = this.presets.find((camera) => vehicleIds.every((id) => carries(camera, id)));
    if (shared && this.camera.value !== shared.id) {
      this.camera.value = shared.id;
      this.onChange();
    }
  }

  /** Takes the settings an opened file gives (its camera offered as "From <file>"). */
  applyFile(fields: Partial<SurveyRequest>, fileName: string): void {
    if (fields.camera) this.chosenByHand = true; // the file's camera is the operator's choice
    if (typeof fields.camera === "string") this.camera.value = fields.camera;
    else if (fields.camera) {
      this.fileCamera = fields.camera;
      this.camera.querySelector('option[value="file"]')?.remove();
      // A QGC manual camera has no figures: its spacing and trigger distance are the plan.
      const manual = "lane_spacing_m" in fields.camera ? fields.camera : null;
      const label = manual
        ? `From ${fileName} (manual: lanes ${manual.lane_spacing_m} m apart, a photo every ${manual.trigger_distance_m} m)`
        : `From ${fileName}`;
      this.camera.append(new Option(label, "file"));
      this.camera.value = "file";
    }
    if (fields.altitude_m != null) [this.heightKind.value, this.height.value] = ["altitude", String(fields.altitude_m)];
    else if (fields.gsd_cm != null) [this.heightKind.value, this.height.value] = ["gsd", String(fields.gsd_cm)];
    if (fields.side_overlap_pct != null) this.side.value = String(fields.side_overlap_pct);
    if (fields.front_overlap_pct != null) this.front.value = String(fields.front_overlap_pct);
    if (fields.angle_deg != null) this.angle.value = String(fields.angle_deg);
  }

  /** The settings as the hub's request takes them. */
  settings(): SurveySettings {
    const number = (input: HTMLInputElement) => Number.parseFloat(input.value);
    const height = number(this.height);
    return {
      camera: this.camera.value === "file" && this.fileCamera ? this.fileCamera : this.camera.value,
      altitude_m: this.heightKind.value === "altitude" ? height : null,
      gsd_cm: this.heightKind.value === "gsd" ? height : null,
      side_overlap_pct: number(this.side),
      front_overlap_pct: number(this.front),
      angle_deg: this.angle.value.trim() === "" ? null : number(this.angle),
      speed_ms: number(this.speed),
    } as SurveySettings;
  }
}
