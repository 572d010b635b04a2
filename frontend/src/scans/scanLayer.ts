// The selected vehicle's latest LIDAR scan as points on the map, and the obstacles the
// hub found in its point map as outlines. It subscribes to one vehicle's scans at a time
// (the hub sends scans to no one who did not ask), draws at most a few times a second on
// a canvas, and keeps only the newest scan.
import * as L from "leaflet";
import { apiUrl } from "../hub/api";
import type { ClientToHub } from "../hub/types";
import type { DashboardStore } from "../store/dashboardStore";
import { decodeScan } from "./scanFrame";

const DRAW_EVERY_MS = 200;
const OBSTACLES_EVERY_MS = 5000;

interface Obstacle {
  id: number;
  outline: [number, number][];
}

export class ScanLayer {
  private readonly points: L.LayerGroup;
  private readonly obstacles: L.LayerGroup;
  private readonly renderer = L.canvas({ padding: 0.2 });
  private vehicleId: string | null = null;
  private drawnAt = 0;
  private obstacleTimer: number | undefined;
  /** Points drawn from the last scan, for the page's tests and the curious. */
  drawn = 0;

  constructor(
    private readonly map: L.Map,
    private readonly send: (message: ClientToHub) => void,
    store: DashboardStore,
  ) {
    this.points = L.layerGroup().addTo(map);
    this.obstacles = L.layerGroup().addTo(map);
    store.subscribe((state) => state.selection.id, (id) => this.follow(id));
  }

  /** Shows this vehicle's scans (null: none). */
  follow(vehicleId: string | null): void {
    if (vehicleId === this.vehicleId) return;
    if (this.vehicleId) this.send({ type: "unsubscribe_scans", vehicle_id: this.vehicleId });
    this.vehicleId = vehicleId;
    this.points.clearLayers();
    this.drawn = 0;
    window.clearInterval(this.obstacleTimer);
    this.obstacles.clearLayers();
    if (!vehicleId) return;
    this.send({ type: "subscribe_scans", vehicle_id: vehicleId });
    void this.refreshObstacles();
    this.obstacleTimer = window.setInterval(() => void this.refreshObstacles(), OBSTACLES_EVERY_MS);
  }

  /** After a reconnect the hub has forgotten the subscription: ask again. */
  resubscribe(): void {
    if (this.vehicleId) this.send({ type: "subscribe_scans", vehicle_id: this.vehicleId });
  }

  onFrame(data: ArrayBuffer): void {
    const now = performance.now();
    if (now - this.drawnAt < DRAW_EVERY_MS) return; // newest wins; the next one is 0.1 s away
    const scan = decodeScan(data);
    if (!scan || scan.vehicleId !== this.vehicleId) return;
    this.drawnAt = now;
    this.points.clearLayers();
    for (const point of scan.points) {
      L.circleMarker(point, {
        renderer: this.renderer,
        radius: 1.5,
        stroke: false,
        fillColor: "#e4572e",
        fillOpacity: 0.9,
        interactive: false,
      }).addTo(this.points);
    }
    this.drawn = scan.points.length;
    this.map.getContainer().dataset.scanPoints = String(this.drawn);
  }

  private async refreshObstacles(): Promise<void> {
    let found: Obstacle[];
    try {
      const response = await fetch(apiUrl("scans/obstacles"), { credentials: "same-origin" });
      if (!response.ok) return;
      found = (await response.json()) as Obstacle[];
    } catch {
      return; // the next round tries again
    }
    this.obstacles.clearLayers();
    for (const obstacle of found) {
      L.polygon(obstacle.outline, {
        renderer: this.renderer,
        color: "#ffd166",
        weight: 1.5,
        fill: false,
        interactive: false,
      }).addTo(this.obstacles);
    }
    this.map.getContainer().dataset.obstacles = String(found.length);
  }

  destroy(): void {
    this.follow(null);
    this.points.remove();
    this.obstacles.remove();
  }
}
