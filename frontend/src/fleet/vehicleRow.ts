// One vehicle's row in the fleet table. Built once; `update` only touches the
// cells whose text changed, so 10 Hz updates stay cheap.
import type { CommandFeedback } from "../hub/commands";
import {
  LINK_LABELS,
  formatAltitude,
  formatArmed,
  formatBattery,
  formatGps,
  formatLanded,
  formatLastSeen,
  formatSpeed,
  isAirborne,
  linkState,
  MISSING,
  readinessTitle,
} from "../ui/format";
import type { Command, VehicleSummary } from "../hub/types";

export type CommandRunner = (vehicleId: string, command: Command) => Promise<CommandFeedback>;

const TELEMETRY_FIELDS = ["mode", "armed", "landed_state", "alt_rel", "groundspeed", "battery", "gps"] as const;
type TelemetryField = (typeof TELEMETRY_FIELDS)[number];

const ACTIONS = [
  { action: "arm", label: "Arm" },
  { action: "disarm", label: "Disarm" },
  { action: "takeoff", label: "Takeoff" },
  { action: "hold", label: "Hold" },
  { action: "land", label: "Land" },
  { action: "rtl", label: "RTL" },
] as const;
type Action = (typeof ACTIONS)[number]["action"];

const DEFAULT_TAKEOFF_ALTITUDE = "10";
const LOW_BATTERY_PERCENT = 20;

function cell(field: string): HTMLTableCellElement {
  const td = document.createElement("td");
  td.dataset.field = field;
  return td;
}

/** Writes only when the text changed; the title shows text that does not fit. */
function setText(element: HTMLElement, text: string): void {
  if (element.textContent === text) return;
  element.textContent = text;
  element.title = text;
}

/** The take-off altitude, command buttons and result line: only for users who may command. */
interface RowControls {
  altitudeInput: HTMLInputElement;
  buttons: HTMLButtonElement[];
  result: HTMLElement;
}

export class VehicleRow {
  readonly element: HTMLTableRowElement;
  private readonly cells = {} as Record<TelemetryField, HTMLTableCellElement>;
  private readonly idText: HTMLElement;
  private readonly link: HTMLElement;
  private readonly controls: RowControls | null = null;
  private pending = false;
  /** Counts the commands shown: only the latest one's answer may land on the row. */
  private shownCommands = 0;
  private lastSeen: number | null = null;

  /** `runCommand` is null for users without the "command" permission: no controls at all. */
  constructor(
    readonly id: string,
    private readonly runCommand: CommandRunner | null,
  ) {
    const tr = document.createElement("tr");
    tr.className = "vehicle-row";
    tr.dataset.vehicleId = id;
    tr.tabIndex = 0;
    this.element = tr;

    const name = document.createElement("td");
    name.className = "vehicle-name";
    this.idText = document.createElement("strong");
    this.idText.dataset.field = "id";
    this.idText.textContent = id;
    this.link = document.createElement("span");
    this.link.className = "link";
    this.link.dataset.field = "link";
    // Worked out on hover, so an offline vehicle's "seen N s ago" is never stale.
    this.link.addEventListener("mouseenter", () => (this.link.title = formatLastSeen(this.lastSeen)));
    name.append(this.idText, this.link);
    tr.append(name);

    for (const field of TELEMETRY_FIELDS) {
      this.cells[field] = cell(field);
      tr.append(this.cells[field]);
    }

    if (runCommand) {
      const actions = document.createElement("td");
      actions.className = "actions";
      this.controls = this.buildControls(actions);
      tr.append(actions);
    }
  }

  private buildControls(actions: HTMLTableCellElement): RowControls {
    const altitude = document.createElement("label");
    altitude.className = "takeoff-altitude";
    const altitudeInput = document.createElement("input");
    altitudeInput.type = "number";
    altitudeInput.min = "1";
    altitudeInput.max = "500";
    altitudeInput.step = "any";
    altitudeInput.value = DEFAULT_TAKEOFF_ALTITUDE;
    altitudeInput.dataset.field = "takeoff-altitude";
    altitudeInput.setAttribute("aria-label", `Take-off altitude for ${this.id}, metres`);
    altitude.append(altitudeInput, " m");
    actions.append(altitude);
    const buttons: HTMLButtonElement[] = [];
    for (const { action, label } of ACTIONS) {
      const button = document.createElement("button");
      button.type = "button";
      button.dataset.action = action;
      button.textContent = label;
      button.className = `action action-${action}`;
      button.addEventListener("click", () => void this.run(action));
      buttons.push(button);
      actions.append(button);
    }
    const result = document.createElement("output");
    result.className = "command-result";
    result.dataset.field = "command-result";
    result.setAttribute("aria-live", "polite");
    actions.append(result);
    return { altitudeInput, buttons, result };
  }

  update(vehicle: VehicleSummary): void {
    const state = vehicle.state ?? null;
    const link = linkState(vehicle);
    this.element.classList.toggle("offline", link !== "online");
    setText(this.link, LINK_LABELS[link]);
    this.link.dataset.state = link;
    this.lastSeen = vehicle.last_seen ?? null;
    this.idText.title = `${vehicle.id}: ${vehicle.autopilot} ${vehicle.vehicle_type}`;

    setText(this.cells.mode, state?.mode ?? MISSING);
    // The modes come once per connection (the store keeps them): the ones set_mode takes.
    const modesTitle = `${state?.mode ?? MISSING}; modes: ${vehicle.modes.join(", ") || "none reported"}`;
    if (this.cells.mode.title !== modesTitle) this.cells.mode.title = modesTitle;
    setText(this.cells.armed, formatArmed(state));
    this.cells.armed.classList.toggle("is-armed", Boolean(state?.armed));
    const notReady = Boolean(state && !state.armed && state.ready_to_fly === false);
    this.cells.armed.classList.toggle("warn", notReady);
    const readyTitle = readinessTitle(state);
    if (this.cells.armed.title !== readyTitle) this.cells.armed.title = readyTitle;
    setText(this.cells.landed_state, formatLanded(state));
    this.cells.landed_state.classList.toggle("is-airborne", isAirborne(state));
    setText(this.cells.alt_rel, formatAltitude(state?.alt_rel));
    setText(this.cells.groundspeed, formatSpeed(state?.groundspeed));
    setText(this.cells.battery, formatBattery(state));
    const percent = state?.battery_remaining;
    const low = percent !== null && percent !== undefined && percent >= 0 && percent < LOW_BATTERY_PERCENT;
    this.cells.battery.classList.toggle("warn", low);
    setText(this.cells.gps, formatGps(state));
    const source = state?.position_source;
    const gpsTitle = source ? `${formatGps(state)} from ${source}` : formatGps(state);
    if (this.cells.gps.title !== gpsTitle) this.cells.gps.title = gpsTitle;
    this.cells.gps.classList.toggle("warn", Boolean(state && state.gps_fix < 3));
  }

  setSelected(selected: boolean): void {
    this.element.classList.toggle("selected", selected);
    this.element.setAttribute("aria-selected", String(selected));
  }

  private commandFor(action: Action): Command {
    switch (action) {
      case "arm":
        return { name: "arm" };
      case "disarm":
        return { name: "disarm", force: false };
      case "takeoff":
        return { name: "takeoff", altitude: this.controls?.altitudeInput.valueAsNumber ?? Number.NaN };
      case "hold":
        return { name: "hold" };
      case "land":
        return { name: "land" };
      case "rtl":
        return { name: "rtl" };
    }
  }

  private async run(action: Action): Promise<void> {
    if (this.pending || !this.runCommand) return;
    const command = this.commandFor(action);
    this.setPending(true);
    try {
      await this.follow(command, this.runCommand(this.id, command));
    } finally {
      this.setPending(false);
    }
  }

  /**
   * Shows a command sent to this vehicle (from this row or any other panel: a go-to, a
   * mode) and then its answer, unless a newer command has replaced it meanwhile.
   */
  async follow(command: Command, answer: Promise<CommandFeedback>): Promise<void> {
    const shown = ++this.shownCommands;
    this.showResult({ text: `${command.name}: sending…`, tone: "pending" });
    const feedback = await answer;
    if (shown === this.shownCommands) this.showResult(feedback);
  }

  private setPending(pending: boolean): void {
    this.pending = pending;
    this.element.classList.toggle("pending", pending);
    this.element.setAttribute("aria-busy", String(pending));
    for (const button of this.controls?.buttons ?? []) button.disabled = pending;
  }

  private showResult({ text, tone }: CommandFeedback): void {
    const result = this.controls?.result;
    if (!result) return;
    result.textContent = text;
    result.title = text;
    result.dataset.tone = tone;
  }
}
