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

  drawSlots(slots: readonly SlotDrawing[]): void {
    this.slots.clearLayers();
    for (const slot of slots) {
      if (slot.at) {
        L.polyline([slot.at, slot.slot], {
          className: "formation-slot-error",
          color: slot.colour,
          weight: 1,
          dashArray: "2 3",
          interactive: false,
        }).addTo(this.slots);
      }
      L.circleMarker(slot.slot, {
        className: "formation-slot",
        radius: 6,
        color: slot.colour,
        fill: false,
        weight: 2,
        interactive: false,
      }).addTo(this.slots);
    }
  }

  clearSlots(): void {
    this.slots.clearLayers();
  }

  destroy(): void {
    this.route.remove();
    this.slots.remove();
  }
}
