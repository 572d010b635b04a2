// A Leaflet layer that owns one <canvas> (and a box for DOM labels) covering the map's
// view: it pans with the map pane, follows the zoom animation like Leaflet's own
// renderers, and redraws only when told (`requestDraw`), at most once per frame.
// Everything drawn on it is placed in layer points relative to `origin`, which stays
// valid while the map is dragged (the pane moves the canvas with it).
import * as L from "leaflet";

/** Leaflet's private helper, the same one its Canvas and SVG renderers use. */
interface MapInternals {
  _getNewPixelOrigin(center: L.LatLng, zoom: number): L.Point;
}

export abstract class CanvasOverlay extends L.Layer {
  protected readonly root: HTMLDivElement;
  protected readonly canvas: HTMLCanvasElement;
  protected readonly context: CanvasRenderingContext2D;
  /** The layer point of the canvas's top-left corner. */
  protected origin = L.point(0, 0);
  protected size = L.point(0, 0);
  protected leafletMap: L.Map | null = null;
  private center = L.latLng(0, 0);
  private zoom = 0;
  private frame: number | null = null;
  private drawnAt = -Infinity;

  constructor(
    className: string,
    private readonly paneName: string,
    private readonly minIntervalMs = 0,
  ) {
    super();
    this.root = L.DomUtil.create("div", `${className} leaflet-zoom-animated canvas-overlay`);
    this.canvas = L.DomUtil.create("canvas", "canvas-overlay-canvas", this.root);
    this.context = this.canvas.getContext("2d")!;
  }

  onAdd(map: L.Map): this {
    this.leafletMap = map;
    this.getPane(this.paneName)?.appendChild(this.root);
    this.reset();
    return this;
  }

  onRemove(): this {
    this.root.remove();
    if (this.frame !== null) cancelAnimationFrame(this.frame);
    this.frame = null;
    this.leafletMap = null;
    return this;
  }

  getEvents(): { [name: string]: L.LeafletEventHandlerFn } {
    return {
      viewreset: () => this.reset(),
      zoom: () => this.followZoom(),
      moveend: () => this.reset(),
      resize: () => this.reset(),
      zoomanim: (event) => this.animateZoom(event as L.ZoomAnimEvent),
    };
  }

  /**
   * Redraws on an animation frame (several requests, one draw), at most once every
   * `minIntervalMs`: vehicles report at 10 Hz, so drawing them at 60 Hz would show the
   * same positions several times over.
   */
  requestDraw(): void {
    if (this.frame !== null || !this.leafletMap) return;
    const run = (now: number) => {
      if (now - this.drawnAt < this.minIntervalMs - 1) {
        this.frame = requestAnimationFrame(run);
        return;
      }
      this.frame = null;
      this.drawnAt = now;
      if (this.leafletMap) this.draw(this.leafletMap);
    };
    this.frame = requestAnimationFrame(run);
  }

  /** Where a position is on the canvas, in CSS pixels. */
  protected toCanvas(map: L.Map, latlng: L.LatLngExpression): L.Point {
    return map.latLngToLayerPoint(latlng).subtract(this.origin);
  }

  /** Clears the canvas (in CSS pixels from here on) and draws everything. */
  protected abstract draw(map: L.Map): void;

  private reset(): void {
    const map = this.leafletMap;
    if (!map) return;
    this.center = map.getCenter();
    this.zoom = map.getZoom();
    this.size = map.getSize();
    this.origin = map.containerPointToLayerPoint([0, 0]).round();
    L.DomUtil.setPosition(this.root, this.origin);
    const ratio = window.devicePixelRatio || 1;
    const width = Math.round(this.size.x * ratio);
    const height = Math.round(this.size.y * ratio);
    if (this.canvas.width !== width || this.canvas.height !== height) {
      this.canvas.width = width;
      this.canvas.height = height;
      this.canvas.style.width = `${this.size.x}px`;
      this.canvas.style.height = `${this.size.y}px`;
    }
    this.context.setTransform(ratio, 0, 0, ratio, 0, 0);
    if (this.frame !== null) cancelAnimationFrame(this.frame);
    this.frame = null;
    this.draw(map);
  }

  /** A zoom without animation (e.g. pinch): redraw at once. */
  private followZoom(): void {
    const map = this.leafletMap;
    if (map && !(map as unknown as { _animatingZoom?: boolean })._animatingZoom) this.reset();
  }

  /** Scales the drawn frame with the map's zoom animation, as L.Renderer does. */
  private animateZoom(event: L.ZoomAnimEvent): void {
    const map = this.leafletMap;
    if (!map) return;
    const scale = map.getZoomScale(event.zoom, this.zoom);
    const offset = map
      .getSize()
      .multiplyBy(0.5)
      .multiplyBy(-scale)
      .add(map.project(this.center, event.zoom))
      .subtract((map as unknown as MapInternals)._getNewPixelOrigin(event.center, event.zoom));
    L.DomUtil.setTransform(this.root, offset, scale);
  }
}
