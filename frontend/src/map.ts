// The Leaflet map: an optional offline-safe basemap and one marker per vehicle.
import * as L from "leaflet";
import "leaflet/dist/leaflet.css";
import type { HubConfig, VehicleSummary } from "./types";
import { VehicleMarker } from "./vehicleMarker";

const GRID_PX = [320, 64]; // major and minor lines, in the order of style.css
const FIT_MAX_ZOOM = 19; // close enough to tell apart vehicles a few metres apart

function positionOf(vehicle: VehicleSummary): L.LatLng | null {
  const lat = vehicle.state?.lat;
  const lon = vehicle.state?.lon;
  if (lat === null || lat === undefined || lon === null || lon === undefined) return null;
  // 0°N 0°E is an autopilot's "no position yet", never a place to draw a vehicle.
  if (lat === 0 && lon === 0) return null;
  return L.latLng(lat, lon);
}

export class FleetMap {
  private readonly map: L.Map;
  private readonly markers = new Map<string, VehicleMarker>();
  private selectedId: string | null = null;
  private hasFitted = false;
  /** The live view to return to when the replay ends. */
  private liveView: { center: L.LatLng; zoom: number } | null = null;

  constructor(
    private readonly container: HTMLElement,
    config: HubConfig,
    private readonly onSelect: (id: string) => void,
  ) {
    const maxZoom = config.basemap_url ? config.basemap_max_zoom : 22;
    this.map = L.map(container, { maxZoom, worldCopyJump: true }).setView([20, 0], 2);
    L.control.scale({ imperial: false }).addTo(this.map);
    this.addFitControl();

    if (config.basemap_url) {
      L.tileLayer(config.basemap_url, {
        attribution: config.basemap_attribution,
        maxZoom: config.basemap_max_zoom,
      }).addTo(this.map);
    } else {
      // No tiles, so nothing is fetched: a CSS grid that moves with the map instead.
      container.classList.add("no-basemap");
      this.map.on("move zoom viewreset resize", () => this.moveGrid());
      this.moveGrid();
    }
  }

  /** Adds, moves or restyles the vehicles' markers. */
  update(vehicles: Iterable<VehicleSummary>): void {
    for (const vehicle of vehicles) {
      let marker = this.markers.get(vehicle.id);
      // A vehicle that loses its fix keeps its marker at the last known position.
      const position = positionOf(vehicle) ?? marker?.marker.getLatLng();
      if (!position) continue;
      if (!marker) {
        marker = new VehicleMarker(vehicle.id, position, this.onSelect);
        this.markers.set(vehicle.id, marker);
        marker.marker.addTo(this.map);
        marker.setSelected(vehicle.id === this.selectedId);
      }
      marker.update(vehicle, position);
    }
    if (!this.hasFitted && !this.liveView && this.markers.size > 0) {
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
      if (this.hasFitted || this.markers.size === 0) this.map.setView(center, zoom, { animate: false });
      else {
        this.hasFitted = true;
        this.fitFleet();
      }
    }
  }

  remove(id: string): void {
    this.markers.get(id)?.marker.remove();
    this.markers.delete(id);
  }

  select(id: string | null, pan: boolean): void {
    if (this.selectedId) this.markers.get(this.selectedId)?.setSelected(false);
    this.selectedId = id;
    const marker = id ? this.markers.get(id) : undefined;
    if (!marker) return;
    marker.setSelected(true);
    if (pan) this.map.panTo(marker.marker.getLatLng());
  }

  /** Removes the map and its markers, leaving the container empty for a later session. */
  destroy(): void {
    this.map.remove();
    this.markers.clear();
    this.container.classList.remove("no-basemap", "replaying");
    this.container.style.backgroundPosition = "";
  }

  fitFleet(): void {
    const points = [...this.markers.values()].map((m) => m.marker.getLatLng());
    if (points.length === 0) return;
    const zoom = Math.min(FIT_MAX_ZOOM, this.map.getMaxZoom());
    if (points.length === 1) this.map.setView(points[0], zoom);
    else this.map.fitBounds(L.latLngBounds(points), { padding: [48, 48], maxZoom: zoom });
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
