// Every vehicle of the fleet on one canvas: a heading arrow (a dot without a heading),
// coloured by state, drawn in a few batched paths so 1,000 vehicles at 10 Hz cost a
// frame's small change. Labels are DOM elements (text, focusable), one per vehicle,
// `<div class="vehicle-marker" data-vehicle-id=...>`, shown only where they fit: a label
// that would overlap another is hidden and counted on that one ("+3"); clicking the
// count zooms in on the group. Clicking a symbol (or a label) selects the vehicle.
import * as L from "leaflet";
import { linkState } from "../ui/format";
import type { VehicleSummary } from "../hub/types";
import { CanvasOverlay } from "./canvasOverlay";
import { type LabelBox, placeLabels } from "./labels";
import { TRAIL_COLOUR, SELECTED_TRAIL_COLOUR, TrailLayer } from "./trails";
import { vehicleColour } from "../viz3d/colours";

const SYMBOL_PX = 28;
const DRAW_EVERY_MS = 50; // 20 Hz: twice the telemetry rate, a third of the frames
const HIT_PX = 16;
const LABEL_OFFSET = L.point(16, -9); // the label's top-left from the symbol's centre (styles/map.css)
const LABEL_HEIGHT = 20;
const COUNT_ROOM_PX = 30;
const LABEL_FONT = "600 12px system-ui, sans-serif";
// The heading arrow of vehicleSymbol() (vehicleMarker.ts), centred on (0, 0).
const ARROW: ReadonlyArray<readonly [number, number]> = [
  [0, -12],
  [10, 11],
  [0, 5.5],
  [-10, 11],
];

/** The marker's look; `fill` is the state colour, as the fleet table shows it. */
export type MarkerState = "online" | "armed" | "offline";
export const MARKER_FILL: Record<MarkerState, string> = {
  online: "#4fb3ff",
  armed: "#ff8a3d",
  offline: "#6b7785",
};

function markerState(vehicle: VehicleSummary): MarkerState {
  if (linkState(vehicle) !== "online") return "offline";
  return vehicle.state?.armed ? "armed" : "online";
}

function positionOf(vehicle: VehicleSummary): L.LatLng | null {
  const lat = vehicle.state?.lat;
  const lon = vehicle.state?.lon;
  if (lat === null || lat === undefined || lon === null || lon === undefined) return null;
  // 0°N 0°E is an autopilot's "no position yet", never a place to draw a vehicle.
  if (lat === 0 && lon === 0) return null;
  return L.latLng(lat, lon);
}

interface Entry {
  id: string;
  position: L.LatLng;
  heading: number | null;
  state: MarkerState;
  element: HTMLDivElement;
  body: HTMLDivElement;
  count: HTMLButtonElement;
  members: string[];
  shown: boolean;
  labelWidth: number;
  labelAt: L.Point;
}

export class VehicleLayer extends CanvasOverlay {
  private readonly entries = new Map<string, Entry>();
  private readonly labels: HTMLDivElement;
  private selectedId: string | null = null;
  private readonly measure = document.createElement("canvas").getContext("2d")!;

  constructor(
    private readonly onSelect: (id: string) => void,
    private readonly trails: TrailLayer | null,
  ) {
    super("vehicle-layer", "vehicles", DRAW_EVERY_MS);
    this.labels = L.DomUtil.create("div", "vehicle-labels", this.root);
    this.measure.font = LABEL_FONT;
  }

  getEvents(): { [name: string]: L.LeafletEventHandlerFn } {
    return { ...super.getEvents(), click: (event) => this.clickMap(event as L.LeafletMouseEvent) };
  }

  /** Adds or moves the vehicles; returns whether any was new. */
  update(vehicles: Iterable<VehicleSummary>): boolean {
    let added = false;
    for (const vehicle of vehicles) {
      let entry = this.entries.get(vehicle.id);
      // A vehicle that loses its fix keeps its marker at the last known position.
      const position = positionOf(vehicle) ?? entry?.position;
      if (!position) continue;
      if (!entry) {
        entry = this.createEntry(vehicle.id, position);
        this.entries.set(vehicle.id, entry);
        added = true;
      }
      entry.position = position;
      entry.heading = vehicle.state?.heading_deg ?? null;
      const state = markerState(vehicle);
      if (state !== entry.state) {
        entry.state = state;
        entry.body.classList.toggle("armed", state === "armed");
        entry.body.classList.toggle("offline", state === "offline");
      }
      entry.body.classList.toggle("no-heading", entry.heading === null);
      if (positionOf(vehicle)) this.trails?.add(vehicle.id, position.lat, position.lng);
    }
    this.requestDraw();
    return added;
  }

  forget(id: string): void {
    this.entries.get(id)?.element.remove();
    this.entries.delete(id);
    this.trails?.forget(id);
    this.requestDraw();
  }

  select(id: string | null): L.LatLng | null {
    if (this.selectedId) this.entries.get(this.selectedId)?.body.classList.remove("selected");
    this.selectedId = id;
    this.trails?.select(id);
    const entry = id ? this.entries.get(id) : undefined;
    entry?.body.classList.add("selected");
    this.requestDraw();
    return entry?.position ?? null;
  }

  positions(): L.LatLng[] {
    return [...this.entries.values()].map((entry) => entry.position);
  }

  get count(): number {
    return this.entries.size;
  }

  /** The label element of a vehicle (other views may mark it, e.g. with a warning). */
  element(id: string): HTMLElement | undefined {
    return this.entries.get(id)?.element;
  }

  clear(): void {
    for (const entry of this.entries.values()) entry.element.remove();
    this.entries.clear();
  }

  private createEntry(id: string, position: L.LatLng): Entry {
    const element = L.DomUtil.create("div", "vehicle-marker", this.labels);
    element.dataset.vehicleId = id;
    element.hidden = true;
    element.dataset.clusterSize = "1";
    const body = L.DomUtil.create("div", "vehicle-marker-body", element);
    // The vehicle's own colour, as in the 3D view, on its label; the symbol's fill keeps
    // saying online, armed or offline.
    body.style.setProperty("--vehicle-colour", vehicleColour(id));
    const row = L.DomUtil.create("div", "vehicle-label-row", body);
    const label = L.DomUtil.create("button", "vehicle-label", row);
    label.type = "button";
    label.textContent = id;
    label.title = `Select ${id}`;
    const count = L.DomUtil.create("button", "vehicle-cluster-count", row);
    count.type = "button";
    count.hidden = true;
    L.DomEvent.disableClickPropagation(element);
    L.DomEvent.on(label, "click", () => this.onSelect(id));
    L.DomEvent.on(count, "click", () => this.zoomToGroup(id));
    const labelWidth = Math.ceil(this.measure.measureText(id).width) + 16;
    return {
      id,
      position,
      heading: null,
      state: "online",
      element,
      body,
      count,
      members: [],
      shown: false,
      labelWidth,
      labelAt: L.point(NaN, NaN),
    };
  }

  private zoomToGroup(id: string): void {
    const map = this.leafletMap;
    const entry = this.entries.get(id);
    if (!map || !entry) return;
    const points = [entry.position, ...entry.members.flatMap((m) => this.entries.get(m)?.position ?? [])];
    const bounds = L.latLngBounds(points);
    const zoom = Math.min(map.getBoundsZoom(bounds.pad(0.5)), map.getMaxZoom());
    // Vehicles on one spot cannot be pulled apart by zooming: one step more, at least.
    map.setView(bounds.getCenter(), Math.max(zoom, map.getZoom() + 1));
  }

  private clickMap(event: L.LeafletMouseEvent): void {
    const map = this.leafletMap;
    if (!map || map.getContainer().classList.contains("replaying")) return;
    let best: string | null = null;
    let bestDistance = HIT_PX;
    for (const entry of this.entries.values()) {
      const distance = map.latLngToContainerPoint(entry.position).distanceTo(event.containerPoint);
      if (distance <= bestDistance) {
        best = entry.id;
        bestDistance = distance;
      }
    }
    if (best) this.onSelect(best);
  }

  protected draw(map: L.Map): void {
    const context = this.context;
    context.clearRect(0, 0, this.size.x, this.size.y);
    const margin = SYMBOL_PX;
    const onScreen: Array<{ entry: Entry; at: L.Point }> = [];
    for (const entry of this.entries.values()) {
      const at = this.toCanvas(map, entry.position);
      if (at.x < -margin || at.y < -margin || at.x > this.size.x + margin || at.y > this.size.y + margin) {
        continue;
      }
      onScreen.push({ entry, at });
    }
    if (this.trails?.visible) this.drawTrailHeads(map, onScreen);
    this.drawSymbols(onScreen);
    this.placeLabels(onScreen);
  }

  /** From each trail's last stored point to the vehicle, in the trail's newest shade. */
  private drawTrailHeads(map: L.Map, onScreen: Array<{ entry: Entry; at: L.Point }>): void {
    const context = this.context;
    const heads = new Path2D();
    const selected = new Path2D();
    for (const { entry, at } of onScreen) {
      const head = this.trails!.head(entry.id);
      if (!head) continue;
      const from = this.toCanvas(map, [head.lat, head.lon]);
      const path = entry.id === this.selectedId ? selected : heads;
      path.moveTo(from.x, from.y);
      path.lineTo(at.x, at.y);
    }
    context.lineCap = "round";
    for (const [path, colour, width] of [
      [heads, TRAIL_COLOUR, 2],
      [selected, SELECTED_TRAIL_COLOUR, 3.5],
    ] as const) {
      context.lineWidth = width;
      context.strokeStyle = `rgba(${colour}, ${TrailLayer.HEAD_ALPHA})`;
      context.stroke(path);
    }
  }

  /**
   * One small pre-drawn picture per state and 5° of heading, copied into place: a copy
   * is far cheaper than filling and stroking an outline, when the canvas is drawn in
   * software (no GPU) as on a field laptop.
   */
  private drawSymbols(onScreen: Array<{ entry: Entry; at: L.Point }>): void {
    const context = this.context;
    const half = SPRITE_PX / 2;
    let selected: { entry: Entry; at: L.Point } | null = null;
    for (const item of onScreen) {
      if (item.entry.id === this.selectedId) {
        selected = item; // drawn last, on top, with its own outline
        continue;
      }
      const sprite = spriteFor(item.entry.state, item.entry.heading, false);
      context.drawImage(sprite, Math.round(item.at.x - half), Math.round(item.at.y - half), SPRITE_PX, SPRITE_PX);
    }
    if (selected) {
      const sprite = spriteFor(selected.entry.state, selected.entry.heading, true);
      const [x, y] = [Math.round(selected.at.x - half), Math.round(selected.at.y - half)];
      context.drawImage(sprite, x, y, SPRITE_PX, SPRITE_PX);
    }
  }

  private placeLabels(onScreen: Array<{ entry: Entry; at: L.Point }>): void {
    const boxes: LabelBox[] = onScreen.map(({ entry, at }) => ({
      id: entry.id,
      x: at.x + LABEL_OFFSET.x,
      y: at.y + LABEL_OFFSET.y,
      width: entry.labelWidth + COUNT_ROOM_PX, // room for a "+N" beside it
      height: LABEL_HEIGHT,
      priority: entry.id === this.selectedId ? 1 : 0,
    }));
    const layout = placeLabels(boxes);
    const where = new Map(onScreen.map(({ entry, at }) => [entry.id, at]));
    for (const entry of this.entries.values()) {
      const members = layout.get(entry.id);
      const shown = members !== undefined;
      if (shown !== entry.shown) {
        entry.shown = shown;
        entry.element.hidden = !shown;
      }
      if (!shown) {
        entry.members = [];
        continue;
      }
      // Moved by a whole pixel, or it keeps its place: no style work for sub-pixel moves.
      const at = where.get(entry.id)!.round();
      if (at.x !== entry.labelAt.x || at.y !== entry.labelAt.y) {
        entry.labelAt = at;
        entry.element.style.transform = `translate(${at.x - SYMBOL_PX / 2}px, ${at.y - SYMBOL_PX / 2}px)`;
      }
      if (members.length !== entry.members.length || members.some((m, i) => m !== entry.members[i])) {
        entry.count.hidden = members.length === 0;
        entry.count.textContent = `+${members.length}`;
        entry.count.title = `${members.length} more here: ${members.slice(0, 20).join(", ")}. Zoom in`;
        entry.element.dataset.clusterSize = String(members.length + 1);
      }
      entry.members = members;
    }
  }
}

const SPRITE_PX = 32;
const HEADING_STEP = 5;
const sprites = new Map<string, HTMLCanvasElement>();

/** The symbol for a state and heading (rounded to 5°), drawn once and kept. */
function spriteFor(state: MarkerState, heading: number | null, selected: boolean): HTMLCanvasElement {
  const step = heading === null ? -1 : Math.round((((heading % 360) + 360) % 360) / HEADING_STEP) % (360 / HEADING_STEP);
  const key = `${state}:${step}:${selected}`;
  let sprite = sprites.get(key);
  if (sprite) return sprite;
  const ratio = window.devicePixelRatio || 1;
  sprite = document.createElement("canvas");
  sprite.width = sprite.height = Math.ceil(SPRITE_PX * ratio);
  const context = sprite.getContext("2d")!;
  context.scale(ratio, ratio);
  const path = new Path2D();
  addSymbol(path, step < 0 ? null : step * HEADING_STEP, L.point(SPRITE_PX / 2, SPRITE_PX / 2));
  context.fillStyle = MARKER_FILL[state];
  context.fill(path);
  context.lineJoin = "round";
  context.lineWidth = selected ? 2.5 : 1.5;
  context.strokeStyle = selected ? "#ffffff" : "#0b1016";
  context.stroke(path);
  sprites.set(key, sprite);
  return sprite;
}

function addSymbol(path: Path2D, heading: number | null, at: L.Point): void {
  if (heading === null) {
    path.moveTo(at.x + 7, at.y);
    path.arc(at.x, at.y, 7, 0, Math.PI * 2);
    return;
  }
  const radians = (heading * Math.PI) / 180;
  const cos = Math.cos(radians);
  const sin = Math.sin(radians);
  ARROW.forEach(([x, y], index) => {
    const px = at.x + x * cos - y * sin;
    const py = at.y + x * sin + y * cos;
    if (index === 0) path.moveTo(px, py);
    else path.lineTo(px, py);
  });
  path.closePath();
}
