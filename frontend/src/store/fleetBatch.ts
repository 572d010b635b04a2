// The dashboard's copy of the fleet. Changes are batched and handed on (to the store)
// once per animation frame, so dozens of vehicles at 10 Hz cost one render pass.
import type { VehicleChange, VehicleSummary } from "../hub/types";

export interface FleetFrame {
  /** Added or updated since the last frame. */
  changed: readonly VehicleSummary[];
  removed: readonly string[];
  /** The whole fleet now (the batcher's own map: read it, never change it). */
  all: ReadonlyMap<string, VehicleSummary>;
}

export class FleetBatch {
  private readonly vehicles = new Map<string, VehicleSummary>();
  private readonly dirty = new Set<string>();
  private frame: number | null = null;

  constructor(private readonly onFlush: (frame: FleetFrame) => void) {}

  get(id: string): VehicleSummary | undefined {
    return this.vehicles.get(id);
  }

  /** The ids of the vehicles known now. */
  ids(): string[] {
    return [...this.vehicles.keys()];
  }

  /** A full snapshot: vehicles missing from it are dropped. */
  replaceAll(vehicles: VehicleSummary[]): void {
    const incoming = new Set(vehicles.map((v) => v.id));
    for (const id of this.vehicles.keys()) {
      if (!incoming.has(id)) {
        this.vehicles.delete(id);
        this.dirty.add(id);
      }
    }
    for (const vehicle of vehicles) this.put(vehicle);
    this.schedule();
  }

  /** A live update: it leaves out what the hub has sent already (modes, autopilot,
   *  vehicle type), so those are kept from the snapshot or an earlier update. */
  upsert(change: VehicleChange): void {
    const known = this.vehicles.get(change.id);
    this.put({
      ...change,
      autopilot: change.autopilot ?? known?.autopilot ?? "",
      vehicle_type: change.vehicle_type ?? known?.vehicle_type ?? "",
      modes: change.modes ?? known?.modes ?? [],
    });
    this.schedule();
  }

  private put(vehicle: VehicleSummary): void {
    this.vehicles.set(vehicle.id, vehicle);
    this.dirty.add(vehicle.id);
  }

  private schedule(): void {
    if (this.frame === null) this.frame = requestAnimationFrame(() => this.flush());
  }

  private flush(): void {
    this.frame = null;
    const changed: VehicleSummary[] = [];
    const removed: string[] = [];
    for (const id of this.dirty) {
      const vehicle = this.vehicles.get(id);
      if (vehicle) changed.push(vehicle);
      else removed.push(id);
    }
    this.dirty.clear();
    this.onFlush({ changed, removed, all: this.vehicles });
  }
}
