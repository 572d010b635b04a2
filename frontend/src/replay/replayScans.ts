// A flight's LIDAR scans in the replay: the vehicle's scan taken at or just before the
// replay's instant, read from the hub's store (GET /vehicles/{id}/scans, world points in
// WGS-84) and drawn as points on a canvas. While playing or scrubbing it asks at most
// five times a second, one request at a time, and only when the instant has left what
// the last answer covered; an answer for an older instant or flight is thrown away.
// The map's element carries `data-replay-scan-points` (points drawn) for the page's tests.
import * as L from "leaflet";
import { apiUrl } from "../hub/api";

const FETCH_EVERY_MS = 200;
const WINDOW_S = 0.5; // look this far back for the scan in force (a 6-12 Hz sensor)
const HOLD_S = 0.1; // an answer stays right this long after its instant: about one turn
const LIMIT = 10; // scans per answer: more than a 12 Hz sensor takes in the window

interface StoredScan {
  time: number;
  geodetic: [number, number, number][];
}

interface ScanPage {
  scans: StoredScan[];
}

export class ReplayScans {
  private readonly points = L.layerGroup();
  private readonly renderer = L.canvas({ padding: 0.2 });
  private vehicleId: string | null = null;
  private wanted: number | null = null; // the replay's instant, Unix seconds
  // What the last answer covers: from its scan's time (or the window's start) to its instant.
  private coveredFrom = Infinity;
  private coveredTo = -Infinity;
  private busy = false;
  private lastFetchAt = -Infinity;
  private timer: number | undefined;
  private generation = 0;

  constructor(private readonly map: L.Map) {}

  /** Starts showing this vehicle's scans (a newly loaded flight's). */
  show(vehicleId: string): void {
    this.clear();
    this.vehicleId = vehicleId;
    this.points.addTo(this.map);
  }

  clear(): void {
    this.generation++;
    this.vehicleId = null;
    this.wanted = null;
    this.coveredFrom = Infinity;
    this.coveredTo = -Infinity;
    window.clearTimeout(this.timer);
    this.timer = undefined;
    this.points.clearLayers();
    this.points.remove();
    delete this.map.getContainer().dataset.replayScanPoints;
  }

  /** The replay is at `at` (Unix seconds). */
  moveTo(at: number): void {
    if (!this.vehicleId) return;
    this.wanted = at;
    if (at >= this.coveredFrom && at <= this.coveredTo + HOLD_S) return;
    this.schedule();
  }

  private schedule(): void {
    if (this.busy || this.timer !== undefined) return;
    const wait = Math.max(0, this.lastFetchAt + FETCH_EVERY_MS - performance.now());
    this.timer = window.setTimeout(() => {
      this.timer = undefined;
      void this.fetchScan();
    }, wait);
  }

  private async fetchScan(): Promise<void> {
    const at = this.wanted;
    const vehicleId = this.vehicleId;
    if (at === null || !vehicleId) return;
    const generation = this.generation;
    this.busy = true;
    this.lastFetchAt = performance.now();
    try {
      const url = apiUrl(`vehicles/${encodeURIComponent(vehicleId)}/scans`);
      url.searchParams.set("start", (at - WINDOW_S).toFixed(3));
      url.searchParams.set("end", at.toFixed(3));
      url.searchParams.set("limit", String(LIMIT));
      const response = await fetch(url, { credentials: "same-origin" });
      if (response.ok && generation === this.generation) {
        const page = (await response.json()) as ScanPage;
        if (generation === this.generation) this.draw(page.scans.at(-1) ?? null, at);
      }
    } catch {
      // The hub is unreachable: the next move asks again.
    } finally {
      this.busy = false;
    }
    if (generation === this.generation && this.wanted !== null && this.wanted !== at) {
      this.moveTo(this.wanted);
    }
  }

  private draw(scan: StoredScan | null, at: number): void {
    this.coveredFrom = scan ? scan.time : at - WINDOW_S;
    this.coveredTo = at;
    this.points.clearLayers();
    for (const [lat, lon] of scan?.geodetic ?? []) {
      L.circleMarker([lat, lon], {
        renderer: this.renderer,
        radius: 1.5,
        stroke: false,
        fillColor: "#e4572e",
        fillOpacity: 0.9,
        interactive: false,
      }).addTo(this.points);
    }
    this.map.getContainer().dataset.replayScanPoints = String(scan?.geodetic.length ?? 0);
  }
}
