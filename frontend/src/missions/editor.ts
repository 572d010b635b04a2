// The mission panel: shows the selected vehicle's mission, and edits one on the map.
//
// Click the map to add a waypoint, drag a marker to move it, click a leg to insert one,
// delete from the list; altitude (with its frame) and speed per item; take-off, loiter
// time, land and RTL items. Every edit is checked by the hub's rails (`mission-check`,
// debounced) and each refusal shows on the items it names. Upload to the vehicle being
// edited (or to others the operator ticks on purpose, each checked against its own rails
// first), download from the vehicle, and open or save a QGroundControl `.plan` file.
//
// A speed is MAVLink's own: a DO_CHANGE_SPEED item before the item it applies to, shown
// folded into that item's row, so the list is always the mission that is sent.
import * as L from "leaflet";
import { ApiError, violationsOf } from "../hub/api";
import type { VehicleSummary } from "../hub/types";
import { checkMission, downloadMission, uploadMission } from "./api";
import { MissionLayer } from "./missionLayer";
import {
  CMD,
  EDITABLE_COMMANDS,
  type MissionCheck,
  type MissionItem,
  commandName,
  frameName,
  fullItem,
  makeItem,
  speedItem,
} from "./model";
import { PlanError, readPlan, writePlan } from "./plan";
import { button, el } from "../ui/dom";

const CHECK_DELAY_MS = 400;
const DEFAULT_ALT_M = 20;
const GROUND_TYPES = new Set(["rover", "boat", "submarine"]);

function numberInput(field: string, value: number | null, title: string, min = 0): HTMLInputElement {
  const input = el("input", "mission-number", field);
  input.type = "number";
  input.step = "any";
  input.min = String(min);
  input.title = title;
  input.value = value === null ? "" : String(Math.round(value * 10) / 10);
  return input;
}

/** The speed item folded into the row of item `index`, if there is one. */
function speedIndexFor(items: readonly MissionItem[], index: number): number | null {
  const before = index - 1;
  return before >= 0 && items[before].command === CMD.CHANGE_SPEED && items[index].command !== CMD.CHANGE_SPEED
    ? before
    : null;
}

export class MissionEditor {
  readonly element: HTMLElement;
  private readonly layer: MissionLayer;
  private readonly control: L.Control;
  private readonly vehicles = new Map<string, VehicleSummary>();
  /** The missions on the vehicles, as last uploaded from here or downloaded. */
  private readonly known = new Map<string, MissionItem[]>();
  private readonly tried = new Set<string>();
  private selectedId: string | null = null;
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
      insert: (index, at) => this.edit((items) => items.splice(index, 0, this.waypointAt(at, items, index))),
      pick: (index) => this.focusRow(index),
    });

    this.element = el("div", "mission-panel");
    const toggle = button("mission-toggle", "Mission", "Show or edit the selected vehicle's mission");
    this.body = el("div", "mission-body");
    this.body.hidden = true;
    toggle.addEventListener("click", () => {
      this.body.hidden = !this.body.hidden;
      toggle.setAttribute("aria-expanded", String(!this.body.hidden));
    });
    this.title = el("div", "mission-title", "mission-vehicle");

    this.editButton = button("mission-edit", "Edit", "Edit this mission on the map (click the map to add waypoints)");
    this.editButton.addEventListener("click", () => (this.draft ? this.stopEditing() : this.startEditing()));
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

    const add = el("div", "mission-add");
    for (const [command, text] of [
      [CMD.TAKEOFF, "+ Take-off"],
      [CMD.LOITER_TIME, "+ Loiter"],
      [CMD.LAND, "+ Land"],
      [CMD.RTL, "+ RTL"],
    ] as const) {
      const adder = button(`mission-add-${command}`, text, `Add a ${commandName(command)} item at the end`);
      adder.addEventListener("click", () => this.edit((items) => items.push(this.newItem(command, items))));
      add.append(adder);
    }
    const clear = button("mission-clear", "Clear", "Remove every item of the plan being edited");
    clear.addEventListener("click", () => this.edit((items) => items.splice(0)));
    add.append(clear);

    const tools = el("div", "mission-toolbar");
    tools.append(this.editButton, download, open, save);
    if (canCommand) tools.append(upload);
    const uploadTo = el("div", "mission-upload-to");
    const uploadLabel = el("span", "mission-upload-label");
    uploadLabel.textContent = "Upload to";
    uploadTo.append(uploadLabel, this.targets);
    uploadTo.hidden = !canCommand;
    this.list = el("ol", "mission-items", "mission-items");
    this.verdict = el("div", "mission-check", "mission-check");
    this.status = el("div", "mission-status", "mission-status");
    this.status.setAttribute("role", "status");
    const hint = el("p", "mission-hint");
    hint.textContent = "Editing: click the map to add a waypoint, drag one to move it, click a leg to insert one.";
    this.body.append(this.title, tools, uploadTo, add, hint, this.list, this.verdict, this.status, this.fileInput);
    this.element.append(toggle, this.body);
    L.DomEvent.disableClickPropagation(this.element);
    L.DomEvent.disableScrollPropagation(this.element);

    const Panel = L.Control.extend({ onAdd: () => this.element });
    this.control = new Panel({ position: "topright" });
    this.control.addTo(map);
    map.on("click", this.onMapClick);
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
    this.map.off("click", this.onMapClick);
    this.control.remove();
    this.layer.destroy();
  }

  // ------------------------------------------------------------------ editing

  private startEditing(): void {
    const vehicle = this.selected();
    const base = this.selectedId ? this.known.get(this.selectedId) : undefined;
    this.draft = base ? base.map((item) => ({ ...item })) : [];
    if (this.draft.length === 0 && vehicle && !GROUND_TYPES.has(vehicle.vehicle_type)) {
      const launch = this.launchPoint();
      this.draft.push(makeItem(CMD.TAKEOFF, launch.lat, launch.lon, DEFAULT_ALT_M));
    }
    this.body.hidden = false;
    this.changed();
  }

  private stopEditing(): void {
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

  private readonly onMapClick = (event: L.LeafletMouseEvent): void => {
    if (!this.draft) return;
    this.edit((items) => items.push(this.waypointAt(event.latlng, items, items.length)));
  };

  private lastAltitude(items: readonly MissionItem[], before: number): number {
    for (let i = before - 1; i >= 0; i--) {
      const item = items[i];
      if (item.command !== CMD.CHANGE_SPEED && item.command !== CMD.RTL && item.alt > 0) return item.alt;
    }
    return DEFAULT_ALT_M;
  }

  private waypointAt(at: L.LatLng, items: readonly MissionItem[], index: number): MissionItem {
    return makeItem(CMD.WAYPOINT, at.lat, at.lng, this.lastAltitude(items, index));
  }

  private newItem(command: number, items: readonly MissionItem[]): MissionItem {
    const alt = command === CMD.RTL || command === CMD.LAND ? 0 : this.lastAltitude(items, items.length);
    const item = makeItem(command, 0, 0, alt);
    if (command === CMD.TAKEOFF) Object.assign(item, this.launchPoint());
    if (command === CMD.LOITER_TIME) {
      // Loiter where the previous place was (a loiter at 0, 0 would be "here").
      const last = [...items].reverse().find((i) => i.lat !== 0 || i.lon !== 0);
      const here = this.selected()?.state;
      Object.assign(item, { param1: 30, lat: last?.lat ?? here?.lat ?? 0, lon: last?.lon ?? here?.lon ?? 0 });
    }
    return item;
  }

  private setCommand(index: number, command: number): void {
    this.edit((items) => {
      const item = items[index];
      const place = item.lat !== 0 || item.lon !== 0;
      item.command = command;
      if (command === CMD.TAKEOFF) Object.assign(item, this.launchPoint());
      if (command === CMD.RTL) Object.assign(item, { lat: 0, lon: 0 });
      if (command === CMD.RTL) item.alt = 0;
      if (command === CMD.LOITER_TIME && !((item.param1 ?? 0) > 0)) item.param1 = 30;
      if ((command === CMD.WAYPOINT || command === CMD.LOITER_TIME) && !place) {
        const here = this.selected()?.state;
        Object.assign(item, { lat: here?.lat ?? 0, lon: here?.lon ?? 0 });
      }
      if (command !== CMD.LOITER_TIME) item.param1 = 0;
    });
  }

  private setSpeed(index: number, speed: number | null): void {
    this.edit((items) => {
      const folded = speedIndexFor(items, index);
      if (speed === null || !(speed > 0)) {
        if (folded !== null) items.splice(folded, 1);
      } else if (folded !== null) items[folded].param2 = speed;
      else items.splice(index, 0, speedItem(speed));
    });
  }

  private deleteRow(index: number): void {
    this.edit((items) => {
      const folded = speedIndexFor(items, index);
      items.splice(folded ?? index, folded === null ? 1 : 2);
    });
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
    this.refusals = new Map();
    for (const violation of check?.violations ?? []) {
      for (const seq of violation.items ?? []) {
        const list = this.refusals.get(seq) ?? [];
        list.push(`${violation.rule}: ${violation.message}`);
        this.refusals.set(seq, list);
      }
    }
    this.verdict.replaceChildren();
    this.verdict.dataset.state = problem ? "error" : check === null ? "" : check.ok ? "ok" : "refused";
    if (problem) this.verdict.textContent = problem;
    else if (check) {
      const head = el("div", "mission-verdict", "mission-verdict");
      const estimate = check.estimate;
      const battery = estimate ? ` · needs about ${Math.round(estimate.required_pct)}% battery` : "";
      head.textContent = check.ok ? `Rails: OK${battery}` : "Refused by the rails:";
      this.verdict.append(head);
      const list = el("ul", "mission-violations");
      for (const violation of check.violations) {
        const line = el("li", "mission-violation");
        line.dataset.rule = violation.rule;
        line.textContent = `${violation.rule}: ${violation.message}`;
        list.append(line);
      }
      this.verdict.append(list);
    }
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
    downloadMission(id)
      .then((result) => {
        if (!this.destroyed && result.items) this.known.set(id, result.items.slice(1).map(fullItem));
        this.render();
      })
      .catch(() => {});
  }

  private async download(): Promise<void> {
    const id = this.selectedId;
    if (!id) return this.say("Select a vehicle first.");
    this.say(`Reading ${id}'s mission…`);
    try {
      const result = await downloadMission(id);
      // Item 0 is home, the vehicle's own.
      const items = (result.items ?? []).slice(1).map(fullItem);
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
    const lines = await Promise.all(targets.map((id) => this.uploadTo(id, items)));
    this.say(lines.join("\n"));
    if (this.draft && this.selectedId && this.known.get(this.selectedId) === undefined) return;
    // Uploaded: the map shows the vehicle's mission (and its progress) again.
    if (this.draft && lines.every((line) => line.includes(": uploaded"))) this.stopEditing();
    else this.render();
  }

  /** One target: checked against its own rails and home first, uploaded only if they pass. */
  private async uploadTo(id: string, items: MissionItem[]): Promise<string> {
    const why = (error: unknown): string => {
      const violations = error instanceof ApiError ? violationsOf(error.body) : [];
      if (violations.length) return violations.map((v) => `${v.rule}: ${v.message}`).join("; ");
      return error instanceof Error ? error.message : String(error);
    };
    try {
      const check = await checkMission(id, items);
      if (!check.ok) {
        return `${id}: not uploaded — refused by its rails: ${check.violations.map((v) => `${v.rule}: ${v.message}`).join("; ")}`;
      }
    } catch (error) {
      return `${id}: not uploaded — could not check it (${why(error)})`;
    }
    try {
      const result = await uploadMission(id, items);
      if (result.outcome.status !== "accepted") {
        return `${id}: ${result.outcome.status}${result.outcome.message ? ` — ${result.outcome.message}` : ""}`;
      }
      this.known.set(
        id,
        items.map((item) => ({ ...item })),
      );
      return `${id}: uploaded (${items.length} items)`;
    } catch (error) {
      return `${id}: refused — ${why(error)}`;
    }
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
    const state = this.selected()?.state;
    const home: [number, number, number] | null =
      state?.home_lat != null && state.home_lon != null
        ? [state.home_lat, state.home_lon, state.home_alt_msl ?? 0]
        : null;
    const text = writePlan(items, { home, autopilot: this.selected()?.autopilot });
    const link = document.createElement("a");
    link.href = URL.createObjectURL(new Blob([text], { type: "application/json" }));
    link.download = `${this.selectedId ?? "mission"}.plan`;
    link.click();
    window.setTimeout(() => URL.revokeObjectURL(link.href), 10_000);
  }

  // ------------------------------------------------------------------ drawing

  /** Where a take-off item stands: the vehicle's home, else where it is now, as
   * QGroundControl writes a take-off at the launch point. PX4 flies to a take-off's
   * position once it has climbed (ArduPilot climbs where it stands), so 0, 0 would send
   * it towards 0°N 0°E; with no position known yet it stays 0, 0, which the hub's check
   * refuses on PX4 with the reason. */
  private launchPoint(): { lat: number; lon: number } {
    const state = this.selected()?.state;
    if (state?.home_lat != null && state.home_lon != null) return { lat: state.home_lat, lon: state.home_lon };
    if (state?.lat != null && state.lon != null) return { lat: state.lat, lon: state.lon };
    return { lat: 0, lon: 0 };
  }

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
    this.editButton.textContent = this.draft ? "Done" : "Edit";
    this.body.classList.toggle("editing", this.draft !== null);
    this.map.getContainer().classList.toggle("mission-editing", this.draft !== null);
    this.renderList();
    this.drawnKey = "";
    this.drawMap();
  }

  private renderList(): void {
    const items = this.shownItems() ?? [];
    const editing = this.draft !== null;
    const current = this.draft ? null : (this.selected()?.state?.mission_current ?? null);
    this.list.replaceChildren();
    items.forEach((item, index) => {
      if (
        item.command === CMD.CHANGE_SPEED &&
        index + 1 < items.length &&
        items[index + 1].command !== CMD.CHANGE_SPEED
      ) {
        return; // folded into the next item's row
      }
      const seq = index + 1;
      const folded = speedIndexFor(items, index);
      const row = el("li", "mission-row");
      row.dataset.seq = String(seq);
      row.dataset.command = String(item.command);
      const refusals = [
        ...(this.refusals.get(seq) ?? []),
        ...(folded === null ? [] : (this.refusals.get(folded + 1) ?? [])),
      ];
      row.classList.toggle("refused", refusals.length > 0);
      row.classList.toggle("active", current === seq);

      const number = el("span", "mission-seq");
      number.textContent = String(seq);
      row.append(number);

      if (editing && (EDITABLE_COMMANDS as readonly number[]).includes(item.command)) {
        const kind = el("select", "mission-kind", "command");
        for (const command of EDITABLE_COMMANDS) {
          kind.append(new Option(commandName(command), String(command), false, command === item.command));
        }
        kind.addEventListener("change", () => this.setCommand(index, Number(kind.value)));
        row.append(kind);
      } else {
        const name = el("span", "mission-kind", "command");
        name.textContent = commandName(item.command);
        row.append(name);
      }

      const hasAlt = item.command !== CMD.RTL && item.command !== CMD.CHANGE_SPEED;
      if (hasAlt) {
        const alt = numberInput("alt", item.alt, "Altitude, metres", -1000);
        alt.disabled = !editing;
        alt.addEventListener("change", () => {
          const value = Number.parseFloat(alt.value);
          if (Number.isFinite(value)) this.edit((list) => (list[index].alt = value));
        });
        const frame = el("span", "mission-frame", "frame");
        frame.textContent = `m ${frameName(item.frame)}`;
        row.append(alt, frame);
      }
      if (item.command === CMD.LOITER_TIME) {
        const time = numberInput("loiter-time", item.param1, "Loiter time, seconds");
        time.disabled = !editing;
        time.addEventListener("change", () => {
          const value = Number.parseFloat(time.value);
          if (Number.isFinite(value)) this.edit((list) => (list[index].param1 = value));
        });
        row.append(time, Object.assign(el("span", "mission-unit"), { textContent: "s" }));
      }
      const speedable =
        item.command === CMD.WAYPOINT || item.command === CMD.LOITER_TIME || item.command === CMD.TAKEOFF;
      if (speedable && (editing || folded !== null)) {
        const speed = numberInput(
          "speed",
          folded === null ? null : items[folded].param2,
          "Ground speed from here on, m/s (empty: unchanged)",
        );
        speed.placeholder = "speed";
        speed.disabled = !editing;
        speed.addEventListener("change", () => {
          const value = Number.parseFloat(speed.value);
          this.setSpeed(index, Number.isFinite(value) ? value : null);
        });
        row.append(speed, Object.assign(el("span", "mission-unit"), { textContent: "m/s" }));
      }
      if (item.lat !== 0 || item.lon !== 0) {
        row.dataset.lat = String(item.lat);
        row.dataset.lon = String(item.lon);
      }
      if (editing) {
        const remove = button("delete", "✕", `Delete item ${seq}`);
        remove.addEventListener("click", () => this.deleteRow(index));
        row.append(remove);
      }
      if (refusals.length > 0) {
        const why = el("div", "mission-row-refusal", "refusal");
        why.textContent = refusals.join("; ");
        row.append(why);
      }
      this.list.append(row);
    });
    if (items.length === 0) {
      const empty = el("li", "mission-empty");
      empty.textContent = editing
        ? "No items yet: click the map to add a waypoint."
        : "No mission known for this vehicle.";
      this.list.append(empty);
    }
  }

  private focusRow(index: number): void {
    this.body.hidden = false;
    const row = this.list.querySelector<HTMLElement>(`[data-seq="${index + 1}"]`);
    row?.scrollIntoView({ block: "nearest" });
    row?.querySelector<HTMLInputElement>('input[data-field="alt"]')?.focus();
  }

  /** One tick box per vehicle: the edited one ticked and fixed, the others off unless ticked. */
  private renderTargets(): void {
    // The plan's own vehicle first, then the others by name.
    const ids = [...this.vehicles.keys()].sort().sort((a, b) => +(b === this.selectedId) - +(a === this.selectedId));
    const boxes: HTMLElement[] = ids.map((id) => {
      const edited = id === this.selectedId;
      const label = el("label", edited ? "mission-target edited" : "mission-target");
      const box = el("input", "mission-target-box");
      box.type = "checkbox";
      box.value = id;
      box.checked = edited || this.extraTargets.has(id);
      box.disabled = edited; // the plan's own vehicle is always a target
      box.addEventListener("change", () => {
        if (box.checked) this.extraTargets.add(id);
        else this.extraTargets.delete(id);
      });
      const name = el("span", "mission-target-name");
      name.textContent = edited ? `${id} (this plan's)` : id;
      label.append(box, name);
      return label;
    });
    if (boxes.length === 0) {
      const none = el("span", "mission-target-none");
      none.textContent = "no vehicle";
      boxes.push(none);
    }
    this.targets.replaceChildren(...boxes);
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
    const home =
      state?.home_lat != null && state.home_lon != null
        ? L.latLng(state.home_lat, state.home_lon)
        : state?.lat != null && state.lon != null && !(state.lat === 0 && state.lon === 0)
          ? L.latLng(state.lat, state.lon)
          : null;
    const current = this.draft ? null : (state?.mission_current ?? null);
    // Telemetry comes at several hertz: redraw only when what is drawn changes.
    const key = `${this.draft ? "draft" : "live"}|${current}|${home?.lat.toFixed(6)},${home?.lng.toFixed(6)}`;
    if (key === this.drawnKey) return;
    this.drawnKey = key;
    this.layer.draw({ items, home, current, refusals: this.refusals, editable: this.draft !== null });
    const active = this.list.querySelector(".mission-row.active");
    if (active && String(current) !== (active as HTMLElement).dataset.seq) this.renderList();
    else if (!this.draft && current !== null && !active) this.renderList();
  }
}
