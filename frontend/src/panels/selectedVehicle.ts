// The selected vehicle at a glance: attitude, altitude, ground speed, climb rate,
// distance from home, time in flight, its warnings, and the flight-mode picker.
import type { CommandFeedback } from "../hub/commands";
import { element, field, setText } from "../ui/dom";
import { MISSING, formatAltitude, formatSpeed } from "../ui/format";
import type { Command, VehicleSummary } from "../hub/types";
import { AttitudeIndicator } from "./attitude";
import { distanceM } from "./geo";
import { LEVEL_ICONS, type VehicleWarnings, type WarningLevel } from "./warnings";
import { icon } from "../ui/icons";

export type Runner = (vehicleId: string, command: Command) => Promise<CommandFeedback>;

function formatDuration(seconds: number): string {
  const s = Math.max(0, Math.floor(seconds));
  const h = Math.floor(s / 3600);
  const m = Math.floor((s % 3600) / 60);
  const mm = String(m).padStart(2, "0");
  const ss = String(s % 60).padStart(2, "0");
  return h > 0 ? `${h}:${mm}:${ss}` : `${m}:${ss}`;
}

function formatDistance(metres: number | null): string {
  if (metres === null) return MISSING;
  return metres < 1000 ? `${metres.toFixed(0)} m` : `${(metres / 1000).toFixed(2)} km`;
}

/** Time since the vehicle's own take-off (the hub's `airborne_since`, on the vehicle's
 *  clock, plus how old its newest state is), so a reloaded page does not restart it. */
function flightTime(vehicle: VehicleSummary, ageS: number | null): string {
  const since = vehicle.airborne_since;
  if (since != null && vehicle.last_seen != null) return formatDuration(vehicle.last_seen - since + (ageS ?? 0));
  return vehicle.state?.landed_state === "on_ground" ? "on ground" : MISSING;
}

function stat(label: string, name: string): [HTMLElement, HTMLElement] {
  const value = field("dd", name, { className: "stat-value", textContent: MISSING });
  return [element("div", { className: "stat" }, element("dt", { textContent: label }), value), value];
}

export class SelectedVehiclePanel {
  readonly element: HTMLElement;
  private readonly title: HTMLElement;
  private readonly attitude = new AttitudeIndicator();
  private readonly values: Record<"alt" | "speed" | "climb" | "home" | "flight", HTMLElement>;
  private readonly modeSelect: HTMLSelectElement;
  private readonly modeResult: HTMLOutputElement;
  private readonly warningList: HTMLUListElement;
  private vehicleId: string | null = null;
  private modesKey = "";
  private pending = false;

  /** `runCommand` is null for users who may not command: the picker only shows the mode. */
  constructor(private readonly runCommand: Runner | null) {
    this.title = element("h2", { className: "panel-title", textContent: "No vehicle selected" });
    this.modeSelect = field("select", "mode-picker", { className: "mode-picker", disabled: true });
    this.modeSelect.setAttribute("aria-label", "Flight mode");
    this.modeSelect.addEventListener("change", () => void this.pickMode(this.modeSelect.value));
    this.modeResult = field("output", "mode-result", { className: "command-result" });
    this.modeResult.setAttribute("aria-live", "polite");
    const [alt, altValue] = stat("Altitude", "selected-alt");
    const [speed, speedValue] = stat("Ground speed", "selected-speed");
    const [climb, climbValue] = stat("Climb", "selected-climb");
    const [home, homeValue] = stat("From home", "selected-home");
    const [flight, flightValue] = stat("In flight", "selected-flight-time");
    this.values = { alt: altValue, speed: speedValue, climb: climbValue, home: homeValue, flight: flightValue };
    this.warningList = field("ul", "selected-warnings", { className: "warning-list" });
    this.element = element(
      "section",
      { className: "selected-vehicle" },
      this.title,
      element(
        "label",
        { className: "mode-row" },
        element("span", { textContent: "Mode" }),
        this.modeSelect,
      ),
      this.modeResult,
      element(
        "div",
        { className: "selected-body" },
        this.attitude.element,
        element("dl", { className: "stats" }, alt, speed, climb, home, flight),
      ),
      this.warningList,
    );
    this.element.dataset.panel = "selected-vehicle";
  }

  get selectedId(): string | null {
    return this.vehicleId;
  }

  select(vehicle: VehicleSummary | null): void {
    const id = vehicle?.id ?? null;
    if (id !== this.vehicleId) {
      this.vehicleId = id;
      this.modesKey = "";
      this.modeResult.textContent = "";
      delete this.modeResult.dataset.tone;
    }
    this.element.dataset.vehicleId = id ?? "";
  }

  /** `ageS`: how old the vehicle's newest state is by the browser's clock, null unknown. */
  update(vehicle: VehicleSummary, warnings: VehicleWarnings, ageS: number | null): void {
    if (vehicle.id !== this.vehicleId) return;
    const state = vehicle.state ?? null;
    setText(this.title, `${vehicle.id} · ${vehicle.autopilot} ${vehicle.vehicle_type}`);
    this.updateModes(vehicle);
    this.attitude.update(state?.roll_deg, state?.pitch_deg, state?.heading_deg);
    setText(this.values.alt, formatAltitude(state?.alt_rel));
    setText(this.values.speed, formatSpeed(state?.groundspeed));
    const climb = state?.climb_rate;
    setText(this.values.climb, climb === null || climb === undefined ? MISSING : `${climb > 0 ? "+" : ""}${formatSpeed(climb)}`);
    const home =
      state && state.lat != null && state.lon != null && state.home_lat != null && state.home_lon != null
        ? distanceM(state.lat, state.lon, state.home_lat, state.home_lon)
        : null;
    setText(this.values.home, formatDistance(home));
    setText(this.values.flight, flightTime(vehicle, ageS));

    const key = warnings.warnings.map((w) => `${w.level}:${w.text}`).join("|");
    if (this.warningList.dataset.key !== key) {
      this.warningList.dataset.key = key;
      this.warningList.replaceChildren(
        ...warnings.warnings.map((w) => {
          const li = element("li", { className: "warning-item" }, ...levelIcon(w.level), w.text);
          li.dataset.level = w.level;
          li.dataset.kind = w.kind;
          return li;
        }),
      );
    }
  }

  clear(): void {
    this.select(null);
    setText(this.title, "No vehicle selected");
    this.modeSelect.replaceChildren();
    this.modeSelect.disabled = true;
    for (const value of Object.values(this.values)) setText(value, MISSING);
    this.attitude.update(null, null, null);
    this.warningList.replaceChildren();
    this.warningList.dataset.key = "";
  }

  /** The vehicle's own modes (its autopilot's), the current one selected. */
  private updateModes(vehicle: VehicleSummary): void {
    const current = vehicle.state?.mode ?? "";
    const modes = vehicle.modes.includes(current) || !current ? vehicle.modes : [current, ...vehicle.modes];
    const key = modes.join("\u0000");
    if (key !== this.modesKey) {
      this.modesKey = key;
      this.modeSelect.replaceChildren(
        ...modes.map((mode) => {
          const option = new Option(mode, mode);
          // A mode the autopilot reports but set_mode does not offer: shown, not pickable.
          option.disabled = !vehicle.modes.includes(mode);
          return option;
        }),
      );
    }
    this.modeSelect.disabled = this.pending || !this.runCommand || !vehicle.connected || vehicle.modes.length === 0;
    // While a change is on its way, the picker keeps the operator's choice.
    if (!this.pending && document.activeElement !== this.modeSelect && this.modeSelect.value !== current) {
      this.modeSelect.value = current;
    }
    this.modeSelect.dataset.current = current;
  }

  private async pickMode(mode: string): Promise<void> {
    const id = this.vehicleId;
    if (!id || !this.runCommand || this.pending) return;
    this.pending = true;
    this.modeSelect.disabled = true;
    this.showResult({ text: `set_mode ${mode}: sending…`, tone: "pending" });
    try {
      const feedback = await this.runCommand(id, { name: "set_mode", mode });
      if (id === this.vehicleId) this.showResult({ ...feedback, text: feedback.text.replace(/^set_mode/, `set_mode ${mode}`) });
    } finally {
      this.pending = false;
      this.modeSelect.disabled = false;
      this.modeSelect.blur(); // the reported mode shows again
    }
  }

  private showResult({ text, tone }: CommandFeedback): void {
    this.modeResult.textContent = text;
    this.modeResult.title = text;
    this.modeResult.dataset.tone = tone;
  }
}

/** A warning level's icon, as the children to put before its text (none when ok). */
function levelIcon(level: WarningLevel): SVGSVGElement[] {
  const name = LEVEL_ICONS[level];
  return name ? [icon(name, level)] : [];
}
