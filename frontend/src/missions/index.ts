// The dashboard's mission tools: the mission panel and editor, "Start mission", and "fly here".
import type * as L from "leaflet";
import type { VehicleSummary } from "../hub/types";
import type { DashboardStore } from "../store/dashboardStore";
import { MissionEditor } from "./editor";
import { GoHere } from "./goHere";
import { StartMission } from "./startMission";
import "./missions.css";

export class MissionTools {
  private readonly editor: MissionEditor;
  private readonly goHere: GoHere | null;
  private readonly vehicles = new Map<string, VehicleSummary>();
  private selectedId: string | null = null;

  constructor(map: L.Map, canCommand: boolean, store: DashboardStore) {
    this.editor = new MissionEditor(map, canCommand);
    const selected = () => (this.selectedId ? this.vehicles.get(this.selectedId) : undefined);
    if (canCommand) this.editor.addSection(new StartMission(selected).element);
    this.goHere = canCommand
      ? new GoHere(map, selected)
      : null;
    store.followFleet(this);
    store.subscribe((state) => state.selection.id, (id) => this.select(id));
  }

  update(vehicles: Iterable<VehicleSummary>): void {
    const list = [...vehicles];
    for (const vehicle of list) this.vehicles.set(vehicle.id, vehicle);
    this.editor.update(list);
  }

  remove(id: string): void {
    this.vehicles.delete(id);
    this.editor.remove(id);
  }

  select(id: string | null): void {
    this.selectedId = id;
    this.editor.select(id);
  }

  destroy(): void {
    this.goHere?.destroy();
    this.editor.destroy();
  }
}
