// The geofence on the map: the selected vehicle's effective fence (its own rails, else the
// site's), or the site's when none is selected. A dashed outline the vehicle must stay
// inside; the hub refuses any command that would take it out. Read again on each
// selection and every REFRESH_MS, since another operator may change the rails.
import * as L from "leaflet";
import { request } from "../hub/api";
import type { components } from "../generated/api";

type Rails = components["schemas"]["SafetyRailsModel"];

const REFRESH_MS = 30_000;

export class GeofenceLayer {
  readonly layer = L.layerGroup();
  private vehicleId: string | null = null;
  private asked = 0; // the newest read wins: selections can change faster than answers come
  private readonly timer: number;

  constructor() {
    this.timer = window.setInterval(() => void this.refresh(), REFRESH_MS);
  }

  show(vehicleId: string | null): void {
    this.vehicleId = vehicleId;
    void this.refresh();
  }

  destroy(): void {
    window.clearInterval(this.timer);
    this.layer.clearLayers();
  }

  private async refresh(): Promise<void> {
    const asked = ++this.asked;
    const id = this.vehicleId;
    const path = id ? `vehicles/${encodeURIComponent(id)}/safety-rails` : "safety/rails";
    let rails: Rails;
    try {
      rails = await request<Rails>(path);
    } catch {
      return; // keep what is drawn: a hub away for a moment has not removed the fence
    }
    if (asked !== this.asked) return;
    this.layer.clearLayers();
    const fence = rails.geofence;
    if (!fence) return;
    const ceiling = fence.max_altitude_m ?? rails.max_altitude_m;
    const outline = L.polygon(
      fence.polygon.map((point) => L.latLng(point.lat, point.lon)),
      { className: "geofence", fill: false, dashArray: "8 6", weight: 2, interactive: false },
    );
    outline.addTo(this.layer);
    const [first] = fence.polygon;
    const title = `Geofence${id ? ` of ${id}` : " (site)"}${ceiling != null ? `, ceiling ${ceiling} m` : ""}`;
    L.marker(L.latLng(first.lat, first.lon), {
      icon: L.divIcon({ className: "geofence-label", html: title, iconSize: undefined }),
      interactive: false,
      keyboard: false,
    }).addTo(this.layer);
  }
}
