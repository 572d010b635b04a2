// The Leaflet map: the base maps (map/baseLayers.ts), the trails and the vehicles, all
// of them on canvases (map/trails.ts, map/vehicleLayer.ts).
import * as L from "leaflet";
import "leaflet/dist/leaflet.css";
import { BaseMaps } from "./baseLayers";
import { CursorPosition } from "./cursorPosition";
import { GeofenceLayer } from "./geofence";
import "./map.css";
import { TrailLayer } from "./trails";
import { VehicleLayer } from "./vehicleLayer";
import type { HubConfig, VehicleSummary } from "../hub/types";
import type { DashboardStore } from "../store/dashboardStore";

const GRID_PX = [320, 64]; // major and minor lines, in the order of styles/map.css
const FIT_MAX_ZOOM = 19; // close enough to tell apart vehicles a few metres apart

/** About a vehicle label's width, drawn right of its symbol. */
const LABEL_PX = 90;

export class FleetMap {
  private readonly map: L.Map;
  private readonly vehicles: VehicleLayer;
  private readonly trails: TrailLayer;
  private readonly baseMaps: BaseMaps;
  private readonly geofence = new GeofenceLayer();
  private selectedId: string | null = null;
  private hasFitted = false;
  /** The live view to return to when the replay ends. */
  private liveView: { center: L.LatLng; zoom: number } | null = null;

  constructor(
    private readonly container: HTMLElement,
    config: HubConfig,
    store: DashboardStore,
  ) {
    this.map = L.map(container, { maxZoom: 22, worldCopyJump: true }).setView([20, 0], 2);
    L.control.scale({ imperial: false }).addTo(this.map);
    new CursorPosition().addTo(this.map);
    this.addFitControl();
    // Trails under the mission overlays (400), vehicles over their markers (600).
    this.map.createPane("trails").style.zIndex = "390";
    this.map.createPane("vehicles").style.zIndex = "620";
    this.trails = new TrailLayer();
    this.trails.addTo(this.map);
    this.vehicles = new VehicleLayer((id) => store.select(id, false), this.trails);
    this.vehicles.addTo(this.map);

    // Without tiles nothing is fetched: a CSS grid that moves with the map instead.
    this.map.on("move zoom viewreset resize", () => this.moveGrid());
    this.baseMaps = new BaseMaps(this.map, config, {
      setGrid: (shown) => {
        container.classList.toggle("no-basemap", shown);
        if (shown) this.moveGrid();
      },
      overlays: { Trails: this.trails, Geofence: this.geofence.layer },
    });
    this.geofence.layer.addTo(this.map);
    this.geofence.show(null);
    void this.baseMaps.start();
    store.followFleet(this);
    // Every pick, even of the selected vehicle again: a pick from the list pans to it.
    store.subscribe((state) => state.selection, ({ id, pan }) => this.select(id, pan));
  }

  /** Adds, moves or restyles the vehicles' markers. */
  update(vehicles: Iterable<VehicleSummary>): void {
    const added = this.vehicles.update(vehicles);
    if (added && this.selectedId) this.vehicles.select(this.selectedId);
    if (!this.hasFitted && !this.liveView && this.vehicles.count > 0) {
      this.hasFitted = true;
      this.fitFleet();
    }
  }

  /** The Leaflet map, for the replay's layers. */
  get leaflet(): L.Map {
    return this.map;
  }

  /**
   * In replay mode the live markers stay on the map but faded and not clickable;
   * leaving it brings back the view the map had before.
   */
  setReplaying(replaying: boolean): void {
    this.container.classList.toggle("replaying", replaying);
    if (replaying) {
      this.liveView ??= { center: this.map.getCenter(), zoom: this.map.getZoom() };
    } else if (this.liveView) {
      const { center, zoom } = this.liveView;
      this.liveView = null;
      if (this.hasFitted || this.vehicles.count === 0) this.map.setView(center, zoom, { animate: false });
      else {
        this.hasFitted = true;
        this.fitFleet();
      }
    }
  }

  remove(id: string): void {
    this.vehicles.forget(id);
  }

  select(id: string | null, pan: boolean): void {
    if (id !== this.selectedId) this.geofence.show(id);
    this.selectedId = id;
    const position = this.vehicles.select(id);
    if (position && pan) this.map.panTo(position);
  }

  /** Removes the map and its layers, leaving the container empty for a later session. */
  destroy(): void {
    this.baseMaps.destroy();
    this.geofence.destroy();
    this.vehicles.clear();
    this.map.remove();
    this.container.classList.remove("no-basemap", "replaying");
    this.container.style.backgroundPosition = "";
    delete this.container.dataset.basemap;
  }

  fitFleet(): void {
    const points = this.vehicles.positions();
    if (points.length === 0) return;
    const zoom = Math.min(FIT_MAX_ZOOM, this.map.getMaxZoom());
    // Clear of the buttons along the map's sides (on a phone they take much of it), with
    // room for the labels drawn right of each vehicle.
    const { topLeft, bottomRight } = this.openArea();
    this.map.fitBounds(L.latLngBounds(points), { paddingTopLeft: topLeft, paddingBottomRight: bottomRight, maxZoom: zoom });
  }

  /**
   * After the map's area changed size (a drawer, a docked panel): fits the fleet again if
   * a vehicle is now out of sight or under the map's buttons; a view that still shows them
   * all (the operator's own framing) is kept.
   */
  refitIfHidden(): void {
    const points = this.vehicles.positions();
    if (points.length === 0 || this.container.classList.contains("replaying")) return;
    const { topLeft, bottomRight } = this.openArea();
    const size = this.map.getSize();
    const hidden = points.some((point) => {
      const at = this.map.latLngToContainerPoint(point);
      return at.x < topLeft[0] || at.y < topLeft[1] || at.x > size.x - bottomRight[0] || at.y > size.y - bottomRight[1];
    });
    if (hidden) this.fitFleet();
  }

  /** The margins the map's corner controls take (and a label's width on the right). */
  private openArea(): { topLeft: L.PointTuple; bottomRight: L.PointTuple } {
    const container = this.map.getContainer();
    const box = container.getBoundingClientRect();
    const corner = (name: string) => container.querySelector(`.leaflet-${name}`)?.getBoundingClientRect();
    const left = corner("top.leaflet-left");
    const right = corner("top.leaflet-right");
    const bottom = corner("bottom.leaflet-left");
    const margin = 16;
    const leftPx = left && left.width > 0 ? left.right - box.left : 0;
    const rightPx = right && right.width > 0 ? box.right - right.left : 0;
    const topPx = Math.max(this.overlayBottom(box), 0);
    const bottomPx = bottom && bottom.height > 0 ? box.bottom - bottom.top : 0;
    return {
      topLeft: [Math.min(leftPx, box.width / 3) + margin, Math.min(topPx, box.height / 3) + margin],
      bottomRight: [Math.min(rightPx + LABEL_PX, box.width / 2) + margin, Math.min(bottomPx, box.height / 3) + margin],
    };
  }

  /** How far down the map the buttons laid over its top (the drawer buttons) reach. */
  private overlayBottom(box: DOMRect): number {
    const over = document.querySelector(".drawer-toggles")?.getBoundingClientRect();
    return over && over.height > 0 ? over.bottom - box.top : 48;
  }

  private moveGrid(): void {
    const origin = this.map.getPixelBounds().min;
    if (!origin) return;
    const offset = (value: number, size: number) => -(((value % size) + size) % size);
    this.container.style.backgroundPosition = GRID_PX.flatMap((size) => [
      `${offset(origin.x, size)}px ${offset(origin.y, size)}px`,
      `${offset(origin.x, size)}px ${offset(origin.y, size)}px`,
    ]).join(", ");
  }

  private addFitControl(): void {
    const FitControl = L.Control.extend({
      onAdd: () => {
        const button = L.DomUtil.create("button", "map-button");
        button.type = "button";
        button.textContent = "Fit fleet";
        button.title = "Zoom to show every vehicle";
        button.dataset.action = "fit-fleet";
        L.DomEvent.disableClickPropagation(button);
        L.DomEvent.on(button, "click", () => this.fitFleet());
        return button;
      },
    });
    new FitControl({ position: "topleft" }).addTo(this.map);
  }
}
