// The fleet list: one VehicleRow per vehicle, kept sorted by id, never rebuilt.
import type { VehicleSummary } from "../hub/types";
import { onCommandSent } from "../hub/commands";
import type { DashboardStore } from "../store/dashboardStore";
import { type CommandRunner, VehicleRow } from "./vehicleRow";

const byId = new Intl.Collator(undefined, { numeric: true }).compare; // drone-2 before drone-10

export class FleetTable {
  private readonly rows = new Map<string, VehicleRow>();
  private readonly emptyRow: HTMLTableRowElement | null;
  private selectedId: string | null = null;
  private readonly listeners = new AbortController();
  private readonly unfollowCommands: () => void;

  /** `runCommand` is null for users who may not command: their rows get no controls. */
  constructor(
    private readonly body: HTMLTableSectionElement,
    private readonly runCommand: CommandRunner | null,
    store: DashboardStore,
  ) {
    this.emptyRow = body.querySelector("tr.empty-row");
    store.followFleet(this);
    // A command from elsewhere (a go-to on the map, a mode) replaces the row's last answer.
    this.unfollowCommands = onCommandSent((id, command, answer) => {
      if (this.runCommand) void this.rows.get(id)?.follow(command, answer);
    });
    store.subscribe((state) => state.selection.id, (id) => this.select(id));
    const onSelect = (id: string) => store.select(id, true);
    const { signal } = this.listeners;
    body.addEventListener("click", (event) => {
      const target = event.target as HTMLElement;
      if (target.closest("button, input, label, output")) return;
      const id = target.closest<HTMLElement>("tr[data-vehicle-id]")?.dataset.vehicleId;
      if (id) onSelect(id);
    }, { signal });
    body.addEventListener("keydown", (event) => {
      const target = event.target as HTMLElement;
      if (event.key !== "Enter" || !target.matches("tr[data-vehicle-id]")) return;
      onSelect(target.dataset.vehicleId!);
    }, { signal });
  }

  update(vehicles: Iterable<VehicleSummary>): void {
    for (const vehicle of vehicles) {
      let row = this.rows.get(vehicle.id);
      if (!row) {
        row = new VehicleRow(vehicle.id, this.runCommand);
        this.insertSorted(row);
        row.setSelected(vehicle.id === this.selectedId);
      }
      row.update(vehicle);
    }
    this.toggleEmpty();
  }

  remove(id: string): void {
    this.rows.get(id)?.element.remove();
    this.rows.delete(id);
    this.toggleEmpty();
  }

  select(id: string | null): void {
    if (this.selectedId) this.rows.get(this.selectedId)?.setSelected(false);
    this.selectedId = id;
    const row = id ? this.rows.get(id) : undefined;
    row?.setSelected(true);
    row?.element.scrollIntoView({ block: "nearest" });
  }

  /** Removes every row and the table's listeners (the session ended). */
  destroy(): void {
    this.listeners.abort();
    this.unfollowCommands();
    for (const row of this.rows.values()) row.element.remove();
    this.rows.clear();
    this.selectedId = null;
    this.toggleEmpty();
  }

  private insertSorted(row: VehicleRow): void {
    let next: VehicleRow | undefined;
    for (const other of this.rows.values()) {
      if (byId(other.id, row.id) > 0 && (!next || byId(other.id, next.id) < 0)) next = other;
    }
    this.body.insertBefore(row.element, next?.element ?? null);
    this.rows.set(row.id, row);
  }

  private toggleEmpty(): void {
    if (this.emptyRow) this.emptyRow.hidden = this.rows.size > 0;
  }
}
