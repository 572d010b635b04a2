// The operator's side panel and what it adds to the shared views: the selected
// vehicle, the warning levels, the live event feed; a warning colour and icon on each
// vehicle's row and marker, the newest unacknowledged critical event on its row, a
// warning count in the header, and the drawers that hold the panels on small screens.
// It decorates the row and marker elements by their data-vehicle-id, so the table and
// the map need not know about warnings.
import { element } from "../ui/dom";
import { icon, setIcon } from "../ui/icons";
import { type IncomingEvent, type LogEvent, CRITICAL_SEVERITY, effectiveSeverity } from "../events/eventLog";
import { EventFeed } from "../events/eventFeed";
import type { VehicleSummary } from "../hub/types";
import type { DashboardStore } from "../store/dashboardStore";
import { type Runner, SelectedVehiclePanel } from "./selectedVehicle";
import {
  LEVEL_ICONS,
  type VehicleWarnings,
  type WarningLevel,
  type WarningLevels,
  evaluate,
  loadLevels,
  saveLevels,
  validLevels,
} from "./warnings";
import "./panels.css";
// The drawers that hold these panels on smaller screens: styles/layout.css.

/** Link age changes with the clock, not with messages: look again this often. */
const TICK_MS = 500;
/** MAV_SEVERITY_NOTICE, for the mode and arming changes seen in the state. */
const NOTICE = 5;

interface Tracked {
  vehicle: VehicleSummary;
  warnings: VehicleWarnings;
  batteryFailsafe: boolean;
  /** The newest critical event not yet acknowledged. */
  alert: LogEvent | null;
  acknowledgedId: number;
}

export class OpsPanels {
  readonly element: HTMLElement;
  private readonly selected: SelectedVehiclePanel;
  private readonly feed: EventFeed;
  /** The newest event of the store's log already looked at. */
  private lastEventId = 0;
  private readonly tracked = new Map<string, Tracked>();
  private readonly count: HTMLElement;
  private readonly toggles: HTMLElement;
  private levels: WarningLevels = loadLevels();
  /** Browser clock minus the hub's, plus the least delivery delay seen (link age). */
  private clockOffsetS = Number.POSITIVE_INFINITY;
  private readonly timer: number;
  private readonly listeners = new AbortController();

  constructor(
    private readonly layout: HTMLElement,
    runCommand: Runner | null,
    private readonly store: DashboardStore,
  ) {
    this.selected = new SelectedVehiclePanel(runCommand);
    this.feed = new EventFeed({ title: "Events", vehicleFilter: true, name: "live" });
    this.element = element(
      "aside",
      { className: "ops-panel", id: "ops-panel" },
      this.selected.element,
      this.levelsForm(),
      this.feed.element,
    );
    this.element.setAttribute("aria-label", "Selected vehicle and events");
    layout.append(this.element);

    this.count = element("span", { className: "warning-count", id: "warning-count" });
    this.count.dataset.field = "warning-count";
    this.count.setAttribute("role", "status");
    document.getElementById("vehicle-count")?.after(this.count);

    // On smaller screens the fleet list and these panels are drawers beside the map.
    this.toggles = element(
      "div",
      { className: "drawer-toggles" },
      this.drawerButton("fleet", "Vehicles"),
      this.drawerButton("ops", "Panels"),
    );
    layout.append(this.toggles);
    this.renderCount();
    this.timer = window.setInterval(() => this.refreshAll(), TICK_MS);
    store.subscribe((state) => state.fleet, ({ changed, removed }) => this.update(changed, removed));
    store.subscribe((state) => state.events, (events) => this.onEvents(events));
    // Every pick, even of the selected vehicle again: it brings the feed back to it.
    store.subscribe((state) => state.selection, ({ id }) => this.select(id));
  }

  /** The store's changes, once per animation frame. */
  private update(changed: Iterable<VehicleSummary>, removed: Iterable<string>): void {
    const nowS = Date.now() / 1000;
    for (const id of removed) this.tracked.delete(id);
    const derived: IncomingEvent[] = [];
    for (const vehicle of changed) {
      if (vehicle.last_seen !== null && vehicle.last_seen !== undefined) {
        this.clockOffsetS = Math.min(this.clockOffsetS, nowS - vehicle.last_seen);
      }
      let entry = this.tracked.get(vehicle.id);
      if (!entry) {
        entry = { vehicle, warnings: { level: "ok", warnings: [] }, batteryFailsafe: false, alert: null, acknowledgedId: 0 };
        this.tracked.set(vehicle.id, entry);
      } else {
        derived.push(...stateChanges(entry.vehicle, vehicle, nowS));
      }
      entry.vehicle = vehicle;
      this.refresh(entry, nowS);
    }
    if (derived.length > 0) this.store.addEvents(derived);
    this.feed.offerVehicles(this.tracked.keys());
    this.renderCount();
  }

  private select(id: string | null): void {
    const entry = id ? this.tracked.get(id) : undefined;
    this.selected.select(entry?.vehicle ?? null);
    if (entry) this.refresh(entry, Date.now() / 1000);
    else this.selected.clear();
    this.feed.filterVehicle(id);
  }

  destroy(): void {
    window.clearInterval(this.timer);
    this.listeners.abort();
    this.element.remove();
    this.toggles.remove();
    this.count.remove();
    found.clear();
    this.layout.classList.remove("drawer-fleet", "drawer-ops");
  }

  /** The store's event log changed: alerts from the events not yet looked at. */
  private onEvents(events: readonly LogEvent[]): void {
    const added = events.filter((event) => event.id > this.lastEventId);
    for (const event of added) this.lastEventId = Math.max(this.lastEventId, event.id);
    const nowS = Date.now() / 1000;
    for (const event of added) {
      const entry = this.tracked.get(event.vehicleId);
      if (!entry) continue;
      if (event.category === "battery") entry.batteryFailsafe = true;
      if (effectiveSeverity(event) <= CRITICAL_SEVERITY && event.id > entry.acknowledgedId) {
        if (!entry.alert || event.time >= entry.alert.time) entry.alert = event;
      }
      this.refresh(entry, nowS);
    }
    this.feed.setEvents(events);
    this.renderCount();
  }

  private refreshAll(): void {
    const nowS = Date.now() / 1000;
    for (const entry of this.tracked.values()) this.refresh(entry, nowS);
    this.renderCount();
  }

  private refresh(entry: Tracked, nowS: number): void {
    const { vehicle } = entry;
    const lastSeen = vehicle.last_seen;
    const ageS =
      lastSeen === null || lastSeen === undefined || !Number.isFinite(this.clockOffsetS)
        ? null
        : Math.max(0, nowS - (lastSeen + this.clockOffsetS));
    const percent = vehicle.state?.battery_remaining;
    // A fresh pack (a swap and reboot) clears the autopilot's failsafe.
    if (entry.batteryFailsafe && percent != null && percent > this.levels.batteryLowPercent + 20) entry.batteryFailsafe = false;
    entry.warnings = evaluate(vehicle, ageS, this.levels, entry.batteryFailsafe);
    decorateRow(entry, () => this.acknowledge(entry));
    decorateMarker(vehicle.id, entry.warnings);
    if (this.selected.selectedId === vehicle.id) this.selected.update(vehicle, entry.warnings, ageS);
  }

  private acknowledge(entry: Tracked): void {
    if (entry.alert) entry.acknowledgedId = entry.alert.id;
    entry.alert = null;
    this.refresh(entry, Date.now() / 1000);
  }

  private renderCount(): void {
    let warning = 0;
    let critical = 0;
    const names: string[] = [];
    for (const entry of this.tracked.values()) {
      if (entry.warnings.level === "ok") continue;
      if (entry.warnings.level === "critical") critical++;
      else warning++;
      names.push(`${entry.vehicle.id}: ${entry.warnings.warnings.map((w) => w.text).join(", ")}`);
    }
    const level: WarningLevel = critical > 0 ? "critical" : warning > 0 ? "warning" : "ok";
    const text = level === "ok" ? "no warnings" : String(warning + critical);
    if (this.count.textContent !== text || this.count.dataset.level !== level) {
      const name = LEVEL_ICONS[level];
      this.count.replaceChildren(...(name ? [icon(name, level)] : []), text);
    }
    this.count.dataset.level = level;
    this.count.dataset.count = String(warning + critical);
    this.count.dataset.critical = String(critical);
    this.count.title = names.join("\n") || "No vehicle needs attention";
  }

  private drawerButton(drawer: "fleet" | "ops", label: string): HTMLButtonElement {
    const button = element("button", { type: "button", className: "drawer-toggle", textContent: label });
    button.dataset.action = `drawer-${drawer}`;
    button.setAttribute("aria-expanded", "false");
    button.addEventListener(
      "click",
      () => {
        const open = !this.layout.classList.contains(`drawer-${drawer}`);
        this.layout.classList.remove("drawer-fleet", "drawer-ops");
        this.layout.classList.toggle(`drawer-${drawer}`, open);
        for (const other of this.toggles.querySelectorAll("button")) other.setAttribute("aria-expanded", "false");
        button.setAttribute("aria-expanded", String(open));
      },
      { signal: this.listeners.signal },
    );
    return button;
  }

  private levelsForm(): HTMLElement {
    const input = (name: string, value: number): HTMLInputElement => {
      const box = element("input", { type: "number", min: "0", max: "100", step: "1", value: String(value), className: "level-input" });
      box.dataset.field = name;
      return box;
    };
    const low = input("battery-low-level", this.levels.batteryLowPercent);
    const critical = input("battery-critical-level", this.levels.batteryCriticalPercent);
    const error = element("span", { className: "level-error" });
    const apply = () => {
      const levels = validLevels({ ...this.levels, batteryLowPercent: low.valueAsNumber, batteryCriticalPercent: critical.valueAsNumber });
      error.textContent = levels ? "" : "critical must be below low, both 0–100 %";
      if (!levels) return;
      this.levels = levels;
      saveLevels(levels);
      this.refreshAll();
    };
    low.addEventListener("change", apply, { signal: this.listeners.signal });
    critical.addEventListener("change", apply, { signal: this.listeners.signal });
    return element(
      "details",
      { className: "warning-levels" },
      element("summary", { textContent: "Warning levels" }),
      element("label", {}, "Battery low at ", low, " %"),
      element("label", {}, "critical at ", critical, " %"),
      element("p", { className: "level-note", textContent: `Link stale after ${this.levels.linkStaleS} s, lost after ${this.levels.linkLostS} s.` }),
      error,
    );
  }
}

/** Mode and arming changes, as the state shows them (the agents send no event for them). */
function stateChanges(before: VehicleSummary, after: VehicleSummary, nowS: number): IncomingEvent[] {
  const was = before.state;
  const now = after.state;
  if (!was || !now) return [];
  const time = after.last_seen ?? nowS;
  const events: IncomingEvent[] = [];
  if (was.mode !== now.mode && now.mode !== "UNKNOWN") {
    events.push({ vehicle_id: after.id, time, kind: "mode", severity: NOTICE, text: `mode ${now.mode} (was ${was.mode})` });
  }
  if (was.armed !== now.armed) {
    events.push({ vehicle_id: after.id, time, kind: now.armed ? "armed" : "disarmed", severity: NOTICE, text: now.armed ? "armed" : "disarmed" });
  }
  return events;
}

// The table and the map build their elements lazily and may replace them: look one up
// again only when the one held has left the page (a 1,000-vehicle fleet at 10 Hz).
const found = new Map<string, HTMLElement>();

function find(selector: string): HTMLElement | null {
  const held = found.get(selector);
  if (held?.isConnected) return held;
  const node = document.querySelector<HTMLElement>(selector);
  if (node) found.set(selector, node);
  else found.delete(selector);
  return node;
}

const rowParts = new WeakMap<HTMLElement, { icon: HTMLElement; alert: HTMLElement; text: HTMLElement; ack: HTMLButtonElement; onAck: () => void }>();

function decorateRow(entry: Tracked, onAck: () => void): void {
  const row = find(`#fleet-table tr[data-vehicle-id="${CSS.escape(entry.vehicle.id)}"]`);
  const name = row?.querySelector<HTMLElement>("td.vehicle-name");
  if (!row || !name) return;
  let parts = rowParts.get(row);
  if (!parts) {
    const icon = element("span", { className: "warning-icon" });
    icon.dataset.field = "warning";
    const text = element("span", { className: "row-alert-text" });
    const ack = element("button", { type: "button", className: "row-alert-ack", textContent: "Ack" });
    ack.dataset.action = "acknowledge";
    const alert = element("div", { className: "row-alert" }, text, ack);
    alert.dataset.field = "alert";
    alert.hidden = true;
    name.append(icon, alert);
    const made = { icon, alert, text, ack, onAck };
    ack.addEventListener("click", () => made.onAck());
    rowParts.set(row, made);
    parts = made;
  }
  parts.onAck = onAck;
  const { level, warnings } = entry.warnings;
  if (row.dataset.warning !== level) row.dataset.warning = level;
  setIcon(parts.icon, LEVEL_ICONS[level], level);
  const title = warnings.map((w) => w.text).join("; ");
  if (parts.icon.title !== title) {
    parts.icon.title = title;
    parts.icon.setAttribute("aria-label", title);
  }
  for (const kind of ["battery", "link", "gps", "ekf"] as const) {
    const hit = warnings.find((w) => w.kind === kind)?.level ?? "";
    if ((row.dataset[`warn${kind}`] ?? "") !== hit) row.dataset[`warn${kind}`] = hit;
  }
  const alert = entry.alert;
  parts.alert.hidden = alert === null;
  if (alert) {
    parts.text.textContent = alert.text; // vehicle text: never HTML
    parts.text.title = alert.text;
    parts.alert.dataset.eventId = String(alert.id);
    parts.alert.dataset.category = alert.category;
  }
}

function decorateMarker(id: string, warnings: VehicleWarnings): void {
  const marker = find(`#map .vehicle-marker[data-vehicle-id="${CSS.escape(id)}"]`);
  if (!marker) return;
  const title = warnings.warnings.map((w) => w.text).join("; ");
  if (marker.dataset.warning === warnings.level && marker.dataset.warningTitle === title) return;
  marker.dataset.warning = warnings.level;
  marker.dataset.warningTitle = title;
  let badge = marker.querySelector<HTMLElement>(".marker-warning");
  if (!badge) {
    badge = element("span", { className: "marker-warning" });
    marker.append(badge);
  }
  setIcon(badge, LEVEL_ICONS[warnings.level], warnings.level);
  badge.title = title;
}
