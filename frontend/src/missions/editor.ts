// The mission panel: shows the selected vehicle's mission, and edits one on the map.
//
// Edit: each map click adds a waypoint (the map's one tool until Done, Esc or a fold), a
// click on a leg inserts one, a marker drags; altitude, frame and speed per item. Every edit is checked by the hub's rails (`mission-check`,
// debounced) and each refusal shows on the items it names. Upload to the vehicle being
// edited (or to others the operator ticks on purpose, each checked against its own rails
// first), download from the vehicle, and open or save a QGroundControl `.plan` file.
//
// A speed is MAVLink's own: a DO_CHANGE_SPEED item before the item it applies to, shown
// folded into that item's row, so the list is always the mission that is sent.
import * as L from "leaflet";
import type { VehicleSummary } from "../hub/types";
import { checkMission } from "./api";
import { MissionLayer } from "./missionLayer";
import { MapClicks } from "../map/foldingPanel";
import { missionHome, missionPanelShell } from "./panelShell";
import { CMD, type MissionCheck, type MissionItem, makeItem } from "./model";
import { PlanError, readPlan } from "./plan";
import { type RowEdits, adderButtons, missionRows } from "./itemRows";
import { changeCommand, deleteRow, lastAltitude, newItem, setSpeed, startingPlan } from "./planEdits";
import { targetBoxes } from "./uploadTargets";
import { checkAndUpload, missionOnBoard, savePlanFile } from "./vehicleMissions";
import { refusalsBySeq, verdictParts } from "./verdict";
import { button, el } from "../ui/dom";

const CHECK_DELAY_MS = 400;

export class MissionEditor {
  readonly element: HTMLElement;
  private readonly layer: MissionLayer;
  /** Map clicks add waypoints: one of the map's tools (map/mapTools.ts). */
  private readonly clicks: MapClicks;
  private readonly control: L.Control;
  private readonly vehicles = new Map<string, VehicleSummary>();
  /** The missions on the vehicles, as last uploaded from here or downloaded. */
  private readonly known = new Map<string, MissionItem[]>();
  private readonly tried = new Set<string>();
  private selectedId: string | null = null;
  private readonly rowEdits: RowEdits = {
    setCommand: (index, command) => this.edit((items) => changeCommand(items[index], command, this.selected()?.state)),
    edit: (change) => this.edit(change),
    setSpeed: (index, speed) => this.edit((items) => setSpeed(items, index, speed)),
    deleteRow: (index) => this.edit((items) => deleteRow(items, index)),
  };
  private draft: MissionItem[] | null = null;
  private refusals = new Map<number, string[]>();
  private checkTimer: number | undefined;
  private checkAbort: AbortController | null = null;
  private drawnKey = "";
  private destroyed = false;

  private readonly body: HTMLElement;
  private readonly title: HTMLElement;
  private readonly list: HTMLOListElement;
  private readonly verdict: HTMLElement;
  private readonly status: HTMLElement;
  private readonly targets: HTMLElement;
  /** Vehicles other than the edited one that the operator ticked for this upload. */
  private readonly extraTargets = new Set<string>();
  private readonly editButton: HTMLButtonElement;
  private readonly fileInput: HTMLInputElement;

  constructor(
    private readonly map: L.Map,
    canCommand: boolean,
  ) {
    this.layer = new MissionLayer(map, {
      move: (index, to) => this.edit((items) => Object.assign(items[index], { lat: to.lat, lon: to.lng })),
      insert: (index, at) => this.clicks.active && this.edit((items) => items.splice(index, 0, this.waypointAt(at, items, index))),
      pick: (index) => this.focusRow(index),
    });

    ({ element: this.element, body: this.body, control: this.control } = missionPanelShell(map));
    this.title = el("div", "mission-title", "mission-vehicle");

    this.editButton = button("mission-edit", "Edit", "Edit this mission on the map (click the map to add waypoints)");
    this.editButton.addEventListener("click", () => (this.clicks.active ? this.finishClicks() : this.startEditing()));
    const discard = button("mission-discard", "Discard", "Drop this plan: show the vehicle's mission again");
    discard.addEventListener("click", () => this.stopEditing());
    const download = button("mission-download", "Download", "Read the mission on the vehicle");
    download.addEventListener("click", () => void this.download());
    const upload = button("mission-upload", "Upload", "Send this mission to the vehicles ticked below");
    upload.addEventListener("click", () => void this.upload());
    this.targets = el("div", "mission-targets", "mission-targets");
    this.targets.setAttribute("role", "group");
    this.targets.setAttribute("aria-label", "Upload to");
    const open = button("mission-open", "Open .plan", "Open a QGroundControl .plan file");
    this.fileInput = el("input", "mission-file", "mission-file");
    this.fileInput.type = "file";
    this.fileInput.accept = ".plan,application/json";
    this.fileInput.hidden = true;
    open.addEventListener("click", () => this.fileInput.click());
    this.fileInput.addEventListener("change", () => void this.openFile());
    const save = button("mission-save", "Save .plan", "Save as a QGroundControl .plan file");
    save.addEventListener("click", () => this.save());

    const add = adderButtons(
      (command) => this.edit((items) => items.push(newItem(command, items, this.selected()?.state))),
      () => this.edit((items) => items.splice(0)),
    );

    const tools = el("div", "mission-toolbar");
    tools.append(this.editButton, discard, download, open, save);
    if (canCommand) tools.append(upload);
    const uploadTo = el("div", "mission-upload-to");
    uploadTo.append(Object.assign(el("span", "mission-upload-label"), { textContent: "Upload to" }), this.targets);
    uploadTo.hidden = !canCommand;
    this.list = el("ol", "mission-items", "mission-items");
    this.verdict = el("div", "mission-check", "mission-check");
    this.status = el("div", "mission-status", "mission-status");
    this.status.setAttribute("role", "status");
    const hint = el("p", "mission-hint");
    hint.textContent = "Edit: click the map to add a waypoint, a leg to insert one; drag one to move it.";
    this.body.append(this.title, tools, uploadTo, add, hint, this.list, this.verdict, this.status, this.fileInput);
    const tool = { label: "Adding mission waypoints", owner: this.element, onEnd: () => this.render() };
    this.clicks = new MapClicks(map, (at) => this.addWaypoint(at), tool);
    this.render();
  }

  /** New telemetry: the active item moves, a vehicle comes or goes from the upload list. */
  update(vehicles: Iterable<VehicleSummary>): void {
    let listChanged = false;
    for (const vehicle of vehicles) {
      if (!this.vehicles.has(vehicle.id)) listChanged = true;
      this.vehicles.set(vehicle.id, vehicle);
    }
    if (listChanged) this.renderTargets();
    this.maybeReadMission();
    this.drawMap();
  }

  remove(id: string): void {
    this.vehicles.delete(id);
    this.renderTargets();
  }

  select(id: string | null): void {
    if (id === this.selectedId) return;
    this.selectedId = id;
    // A plan is checked against one vehicle's rails: a newly selected vehicle is the only
    // target until the operator ticks others again (a tick for the last one never carries over).
    this.extraTargets.clear();
    this.renderTargets();
    this.maybeReadMission();
    if (this.draft) this.scheduleCheck();
    this.render();
  }

  destroy(): void {
    this.destroyed = true;
    window.clearTimeout(this.checkTimer);
    this.checkAbort?.abort();
    this.clicks.destroy();
    this.control.remove();
    this.layer.destroy();
  }

  // ------------------------------------------------------------------ editing

  /** A section of the panel's own (Start mission), under the list. */
  addSection(section: HTMLElement): void {
    this.body.insertBefore(section, this.fileInput);
  }

  /** Map clicks add waypoints to the plan (one begun from the vehicle's mission if none is). */
  private startEditing(): void {
    this.draft ??= startingPlan(this.selectedId ? this.known.get(this.selectedId) : undefined, this.selected());
    this.body.hidden = false;
    this.clicks.start();
    this.changed();
  }

  /** Done adding waypoints: the plan stays, to upload, save or discard. */
  private finishClicks(): void {
    this.clicks.stop();
    this.render();
  }

  private stopEditing(): void {
    this.clicks.stop();
    this.draft = null;
    this.refusals = new Map();
    this.checkAbort?.abort();
    this.render();
  }

  /** Applies one change to the plan being edited (starting an edit if none is). */
  private edit(change: (items: MissionItem[]) => void): void {
    if (!this.draft) this.startEditing();
    change(this.draft!);
    this.changed();
  }

  private changed(): void {
    this.render();
    this.scheduleCheck();
  }

  private addWaypoint(at: L.LatLng): void {
    this.edit((items) => items.push(this.waypointAt(at, items, items.length)));
  }

  private waypointAt(at: L.LatLng, items: readonly MissionItem[], index: number): MissionItem {
    return makeItem(CMD.WAYPOINT, at.lat, at.lng, lastAltitude(items, index));
  }

  // ------------------------------------------------------------------ the rails

  private scheduleCheck(): void {
    window.clearTimeout(this.checkTimer);
    this.checkAbort?.abort();
    this.verdict.dataset.state = "pending";
    this.checkTimer = window.setTimeout(() => void this.runCheck(), CHECK_DELAY_MS);
  }

  private async runCheck(): Promise<void> {
    const items = this.draft;
    const vehicleId = this.selectedId;
    if (!items || items.length === 0 || !vehicleId) {
      this.showCheck(null, vehicleId ? "" : "Select a vehicle to check the plan against its rails.");
      return;
    }
    const abort = new AbortController();
    this.checkAbort = abort;
    try {
      const check = await checkMission(vehicleId, items, abort.signal);
      if (abort.signal.aborted || this.destroyed) return;
      this.showCheck(check, "");
    } catch (error) {
      if (abort.signal.aborted || this.destroyed) return;
      this.showCheck(null, `Could not check the plan: ${error instanceof Error ? error.message : String(error)}`);
    }
  }

  private showCheck(check: MissionCheck | null, problem: string): void {
    this.refusals = refusalsBySeq(check);
    this.verdict.replaceChildren();
    this.verdict.dataset.state = problem ? "error" : check === null ? "" : check.ok ? "ok" : "refused";
    if (problem) this.verdict.textContent = problem;
    else if (check) this.verdict.append(...verdictParts(check));
    this.render();
  }

  // ------------------------------------------------------------------ vehicle I/O

  private maybeReadMission(): void {
    // A mission already on the vehicle is read once, so that it shows on the map.
    const id = this.selectedId;
    const vehicle = this.selected();
    if (!id || !vehicle || this.known.has(id) || this.tried.has(id)) return;
    if ((vehicle.state?.mission_total ?? 0) <= 1 || !vehicle.state?.fcu_connected) return;
    this.tried.add(id);
    missionOnBoard(id)
      .then((items) => {
        if (!this.destroyed && items) this.known.set(id, items);
        this.render();
      })
      .catch(() => {});
  }

  private async download(): Promise<void> {
    const id = this.selectedId;
    if (!id) return this.say("Select a vehicle first.");
    this.say(`Reading ${id}'s mission…`);
    try {
      const items = (await missionOnBoard(id)) ?? [];
      this.known.set(id, items);
      if (this.draft) {
        this.draft = items.map((item) => ({ ...item }));
        this.scheduleCheck();
      }
      this.say(`${id}: ${items.length} items read.`);
    } catch (error) {
      this.say(`${id}: could not read its mission (${error instanceof Error ? error.message : String(error)}).`);
    }
    this.render();
  }

  /** The vehicles an upload goes to: the edited one, then any others ticked on purpose. */
  private uploadTargets(): string[] {
    const others = [...this.extraTargets].filter((id) => id !== this.selectedId && this.vehicles.has(id)).sort();
    return this.selectedId ? [this.selectedId, ...others] : others;
  }

  private async upload(): Promise<void> {
    const items = this.draft ?? (this.selectedId ? this.known.get(this.selectedId) : undefined);
    if (!items || items.length === 0) return this.say("Nothing to upload: add items first.");
    const targets = this.uploadTargets();
    if (targets.length === 0) return this.say("Select a vehicle to upload to.");
    this.say(`Checking and uploading to ${targets.join(", ")}…`);
    const lines = await Promise.all(
      targets.map(async (id) => {
        const outcome = await checkAndUpload(id, items);
        if (outcome.uploaded) this.known.set(id, items.map((item) => ({ ...item })));
        return outcome.line;
      }),
    );
    this.say(lines.join("\n"));
    if (this.draft && this.selectedId && this.known.get(this.selectedId) === undefined) return;
    // Uploaded: the map shows the vehicle's mission (and its progress) again.
    if (this.draft && lines.every((line) => line.includes(": uploaded"))) this.stopEditing();
    else this.render();
  }

  private async openFile(): Promise<void> {
    const file = this.fileInput.files?.[0];
    this.fileInput.value = "";
    if (!file) return;
    try {
      const plan = readPlan(await file.text());
      this.draft = plan.items;
      this.body.hidden = false;
      this.say(`${file.name}: ${plan.items.length} items opened.`);
      this.changed();
    } catch (error) {
      const why = error instanceof PlanError ? error.message : String(error);
      this.say(`${file.name} could not be opened: ${why}`);
    }
  }

  private save(): void {
    const items = this.draft ?? (this.selectedId ? this.known.get(this.selectedId) : undefined);
    if (!items || items.length === 0) return this.say("Nothing to save: add items first.");
    savePlanFile(items, this.selected(), this.selectedId ?? "mission");
  }

  // ------------------------------------------------------------------ drawing

  private selected(): VehicleSummary | undefined {
    return this.selectedId ? this.vehicles.get(this.selectedId) : undefined;
  }

  private say(text: string): void {
    this.status.textContent = text;
  }

  private shownItems(): MissionItem[] | null {
    return this.draft ?? (this.selectedId ? (this.known.get(this.selectedId) ?? null) : null);
  }

  private render(): void {
    if (this.destroyed) return;
    const id = this.selectedId;
    this.title.textContent = id
      ? `${this.draft ? "Editing a plan for" : "Mission of"} ${id}`
      : "Select a vehicle to see or edit its mission.";
    this.editButton.textContent = this.clicks.active ? "Done" : "Edit";
    this.editButton.classList.toggle("active", this.clicks.active);
    this.body.classList.toggle("editing", this.draft !== null);
    this.body.classList.toggle("adding", this.clicks.active);
    this.map.getContainer().classList.toggle("mission-editing", this.clicks.active);
    this.renderList();
    this.drawnKey = "";
    this.drawMap();
  }

  private renderList(): void {
    const shown = {
      items: this.shownItems() ?? [],
      editing: this.draft !== null,
      current: this.draft ? null : (this.selected()?.state?.mission_current ?? null),
      refusals: this.refusals,
    };
    this.list.replaceChildren(...missionRows(shown, this.rowEdits));
  }

  private focusRow(index: number): void {
    this.body.hidden = false;
    const row = this.list.querySelector<HTMLElement>(`[data-seq="${index + 1}"]`);
    row?.scrollIntoView({ block: "nearest" });
    row?.querySelector<HTMLInputElement>('input[data-field="alt"]')?.focus();
  }

  /** One tick box per vehicle: the edited one ticked and fixed, the others off unless ticked. */
  private renderTargets(): void {
    this.targets.replaceChildren(...targetBoxes(this.vehicles.keys(), this.selectedId, this.extraTargets));
  }

  private drawMap(): void {
    const items = this.shownItems();
    const vehicle = this.selected();
    const state = vehicle?.state;
    if (!items || items.length === 0) {
      if (this.drawnKey !== "none") this.layer.clear();
      this.drawnKey = "none";
      return;
    }
    const home = missionHome(state);
    const current = this.draft ? null : (state?.mission_current ?? null);
    // Telemetry comes at several hertz: redraw only when what is drawn changes.
    const key = `${this.draft ? "draft" : "live"}|${this.clicks.active}|${current}|${home?.lat.toFixed(6)},${home?.lng.toFixed(6)}`;
    if (key === this.drawnKey) return;
    this.drawnKey = key;
    const editable = this.draft !== null;
    this.layer.draw({ items, home, current, refusals: this.refusals, editable, inserting: this.clicks.active });
    const active = this.list.querySelector(".mission-row.active");
    if (active && String(current) !== (active as HTMLElement).dataset.seq) this.renderList();
    else if (!this.draft && current !== null && !active) this.renderList();
  }
}
