// The formation on the map: the leader's route (dashed while it is drawn, its points
// marked) and each follower's slot around the leader, in the follower's colour, with a
// thin line from the follower to its slot while it is away from it.
import * as L from "leaflet";

export interface SlotDrawing {
  vehicleId: string;
  colour: string;
  slot: [number, number];
  /** Where the follower is, if it reported a position. */
  at: [number, number] | null;
}

export class FormationLayer {
  private readonly route = L.layerGroup();
  private readonly slots = L.layerGroup();
  private readonly drawn = new Map<string, { slot: L.CircleMarker; line: L.Polyline }>();

  constructor(map: L.Map) {
    this.route.addTo(map);
    this.slots.addTo(map);
  }

  drawRoute(points: readonly L.LatLng[], drawing: boolean): void {
    this.route.clearLayers();
    if (points.length === 0) return;
    L.polyline([...points], {
      className: drawing ? "formation-route formation-route-drawing" : "formation-route",
      color: "#74c0fc",
      weight: 3,
      dashArray: drawing ? "4 4" : undefined,
      interactive: false,
    }).addTo(this.route);
    for (const at of points) {
      L.circleMarker(at, {
        className: "formation-route-point",
        radius: 4,
        color: "#74c0fc",
        fillOpacity: 1,
        interactive: false,
      }).addTo(this.route);
    }
  }

  /** Moves the slots' markers (made once per follower: this runs at the telemetry's rate). */
  drawSlots(slots: readonly SlotDrawing[]): void {
    const wanted = new Set(slots.map((slot) => slot.vehicleId));
    for (const [vehicleId, drawn] of this.drawn) {
      if (wanted.has(vehicleId)) continue;
      this.slots.removeLayer(drawn.slot).removeLayer(drawn.line);
      this.drawn.delete(vehicleId);
    }
    for (const slot of slots) {
      let drawn = this.drawn.get(slot.vehicleId);
      if (!drawn) {
        const style = { color: slot.colour, interactive: false };
        drawn = {
          line: L.polyline([], { ...style, className: "formation-slot-error", weight: 1, dashArray: "2 3" }),
          slot: L.circleMarker(slot.slot, { ...style, className: "formation-slot", radius: 6, fill: false, weight: 2 }),
        };
        drawn.line.addTo(this.slots);
        drawn.slot.addTo(this.slots);
        drawn.slot.getElement()?.setAttribute("data-vehicle-id", slot.vehicleId);
        this.drawn.set(slot.vehicleId, drawn);
      }
      drawn.slot.setLatLng(slot.slot);
      drawn.line.setLatLngs(slot.at ? [slot.at, slot.slot] : []);
    }
  }

  clearSlots(): void {
    this.slots.clearLayers();
    this.drawn.clear();
  }

  destroy(): void {
    this.route.remove();
    this.slots.remove();
  }
}
