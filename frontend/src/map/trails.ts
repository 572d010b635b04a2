// Each vehicle's recent track, drawn fading with age: the last few minutes, a point every
// 2 s per vehicle. All trails of one age share one stroke (six strokes for the fleet),
// and the canvas is redrawn at most every 2 s or when the view changes, so a
// thousand trails cost little; the piece from the last point to the vehicle is drawn
// with the vehicle (VehicleLayer), so a trail never lags behind its marker.
import type * as L from "leaflet";
import { CanvasOverlay } from "./canvasOverlay";

export const TRAIL_SECONDS = 180;
const POINT_EVERY_MS = 2000;
const AGE_BANDS = 6;
const REDRAW_EVERY_MS = 2000;
export const TRAIL_COLOUR = "79, 179, 255"; // --accent
export const SELECTED_TRAIL_COLOUR = "255, 255, 255";

interface TrailPoint {
  at: number; // ms, this page's clock
  lat: number;
  lon: number;
}

export class TrailLayer extends CanvasOverlay {
  private readonly trails = new Map<string, TrailPoint[]>();
  private selectedId: string | null = null;
  private lastDraw = 0;
  private timer: number | undefined;

  constructor(private readonly now: () => number = () => performance.now()) {
    super("trail-layer", "trails");
  }

  /** Notes a vehicle's position; keeps one point a second. */
  add(id: string, lat: number, lon: number): void {
    const at = this.now();
    let trail = this.trails.get(id);
    if (!trail) {
      trail = [];
      this.trails.set(id, trail);
    }
    const last = trail[trail.length - 1];
    if (last && at - last.at < POINT_EVERY_MS) return;
    trail.push({ at, lat, lon });
    const oldest = at - TRAIL_SECONDS * 1000;
    let stale = 0;
    while (stale < trail.length && trail[stale].at < oldest) stale++;
    if (stale > 0) trail.splice(0, stale);
    this.scheduleDraw();
  }

  /** The newest stored point, where the vehicle layer's live piece starts. */
  head(id: string): TrailPoint | undefined {
    const trail = this.trails.get(id);
    return trail?.[trail.length - 1];
  }

  /** Alpha of the newest band, for the live piece. */
  static readonly HEAD_ALPHA = 0.7;

  forget(id: string): void {
    this.trails.delete(id);
    this.scheduleDraw();
  }

  select(id: string | null): void {
    this.selectedId = id;
    this.requestDraw();
  }

  get selected(): string | null {
    return this.selectedId;
  }

  get visible(): boolean {
    return this.leafletMap !== null;
  }

  onRemove(): this {
    window.clearTimeout(this.timer);
    this.timer = undefined;
    return super.onRemove();
  }

  /** At most one redraw a second for new points; a view change redraws at once. */
  private scheduleDraw(): void {
    if (this.timer !== undefined || !this.leafletMap) return;
    const wait = Math.max(0, this.lastDraw + REDRAW_EVERY_MS - this.now());
    this.timer = window.setTimeout(() => {
      this.timer = undefined;
      this.requestDraw();
    }, wait);
  }

  protected draw(map: L.Map): void {
    this.lastDraw = this.now();
    const context = this.context;
    context.clearRect(0, 0, this.size.x, this.size.y);
    const oldest = this.lastDraw - TRAIL_SECONDS * 1000;
    const bandMs = (TRAIL_SECONDS * 1000) / AGE_BANDS;
    const bands = Array.from({ length: AGE_BANDS }, () => new Path2D());
    const selected = Array.from({ length: AGE_BANDS }, () => new Path2D());
    for (const [id, trail] of this.trails) {
      if (trail.length < 2) continue;
      const paths = id === this.selectedId ? selected : bands;
      // One polyline per band of each trail: a new subpath only where the band changes.
      let previous = this.toCanvas(map, [trail[0].lat, trail[0].lon]);
      let current = -1;
      for (let index = 1; index < trail.length; index++) {
        const point = trail[index];
        const here = this.toCanvas(map, [point.lat, point.lon]);
        if (point.at >= oldest) {
          const band = Math.min(AGE_BANDS - 1, Math.floor((this.lastDraw - point.at) / bandMs));
          if (band !== current) {
            paths[band].moveTo(previous.x, previous.y);
            current = band;
          }
          paths[band].lineTo(here.x, here.y);
        }
        previous = here;
      }
    }
    context.lineCap = "round";
    context.lineJoin = "round";
    for (const [paths, colour, width] of [
      [bands, TRAIL_COLOUR, 2],
      [selected, SELECTED_TRAIL_COLOUR, 3.5],
    ] as const) {
      context.lineWidth = width;
      paths.forEach((path, band) => {
        // Newest band most opaque; the oldest nearly gone.
        const alpha = TrailLayer.HEAD_ALPHA * (1 - band / AGE_BANDS);
        context.strokeStyle = `rgba(${colour}, ${alpha.toFixed(3)})`;
        context.stroke(path);
      });
    }
  }
}
