// The survey on the map: the area being drawn (outline and holes), the planned lanes in
// one colour per drone, and during the flight the lanes flown (faded) and the photos
// (dots where CAMERA_FEEDBACK placed them), over the live orthomosaic the hub builds from
// the photos (a tile layer whose tiles are asked again whenever a photo lands).
//
// Plain Leaflet vectors, as the mission editor draws: clicks add vertices to the ring
// being drawn, a click on its first vertex (or "Close ring") closes it. No drawing plugin
// is installed, and a polygon with holes is all this needs.
import * as L from "leaflet";

import type { DashboardStore } from "../store/dashboardStore";
import type { MosaicDetail } from "./api";
import { FinishedMosaics } from "./finishedMosaics";
import { mosaicBounds, mosaicLayer, mosaicUrl } from "./mosaicTiles";

export interface LaneDrawing {
  vehicleId: string;
  colour: string;
  /** [[lat, lon], [lat, lon]] from start to end. */
  path: [number, number][];
  done: boolean;
}

export class SurveyLayer {
  private readonly area = L.layerGroup();
  private readonly plan = L.layerGroup();
  private readonly photos = L.layerGroup();
  private mosaic: L.TileLayer | null = null;
  private mosaicUrl = "";

  private readonly finished: FinishedMosaics;

  constructor(
    private readonly map: L.Map,
    store: DashboardStore,
  ) {
    this.finished = new FinishedMosaics(map, store);
    this.plan.addTo(map);
    this.photos.addTo(map);
    this.area.addTo(map);
  }

  /** Closed rings (outline first, then holes) and the ring being drawn, if any. */
  drawArea(rings: readonly L.LatLng[][], open: readonly L.LatLng[] | null, onCloseRing: () => void): void {
    this.area.clearLayers();
    rings.forEach((ring, index) => {
      L.polygon(ring, {
        className: index === 0 ? "survey-area" : "survey-hole",
        color: index === 0 ? "#ffd43b" : "#ff6b6b",
        weight: 2,
        fillOpacity: index === 0 ? 0.08 : 0.25,
        interactive: false,
      }).addTo(this.area);
    });
    if (open && open.length > 0) {
      L.polyline([...open], { className: "survey-drawing", color: "#ffd43b", dashArray: "4 4", interactive: false }).addTo(
        this.area,
      );
      open.forEach((at, index) => {
        const vertex = L.circleMarker(at, {
          className: index === 0 ? "survey-vertex survey-vertex-first" : "survey-vertex",
          radius: index === 0 ? 7 : 4,
          color: "#ffd43b",
          fillOpacity: 1,
          // The first vertex closes the ring; the others must not swallow the map's click.
          interactive: index === 0,
          bubblingMouseEvents: false,
        });
        if (index === 0) vertex.on("click", () => onCloseRing());
        vertex.addTo(this.area);
      });
    }
  }

  drawLanes(lanes: readonly LaneDrawing[]): void {
    this.plan.clearLayers();
    for (const lane of lanes) {
      L.polyline(lane.path, {
        className: lane.done ? "survey-lane survey-lane-done" : "survey-lane",
        color: lane.colour,
        weight: 3,
        opacity: lane.done ? 0.25 : 0.9,
        interactive: false,
      }).addTo(this.plan);
    }
  }

  drawPhotos(photos: readonly { at: [number, number]; colour: string }[]): void {
    this.photos.clearLayers();
    for (const photo of photos) {
      L.circleMarker(photo.at, {
        className: "survey-photo",
        radius: 2,
        color: photo.colour,
        fillOpacity: 1,
        weight: 1,
        interactive: false,
      }).addTo(this.photos);
    }
  }

  /** The survey's orthomosaic, above the base map: `revision` (photos applied) is in the
   * tile URL, so each new photo has Leaflet ask for the tiles again; the hub answers the
   * unchanged ones with a 304 (their ETag is their version). */
  showMosaic(mosaic: MosaicDetail): void {
    const url = mosaicUrl(mosaic);
    if (url === this.mosaicUrl || mosaic.max_zoom === null || mosaic.max_zoom === undefined) return;
    this.mosaicUrl = url;
    if (this.mosaic) {
      // The mosaic grows: Leaflet reads `bounds` for every tile it considers, so the new
      // outline's box lets it ask for the tiles the latest photos added.
      const bounds = mosaicBounds(mosaic);
      if (bounds) this.mosaic.options.bounds = bounds;
      this.mosaic.setUrl(url);
      return;
    }
    this.mosaic = mosaicLayer(this.map, mosaic)?.addTo(this.map) ?? null;
  }

  clearMosaic(): void {
    this.mosaic?.remove();
    this.mosaic = null;
    this.mosaicUrl = "";
  }

  clearPlan(): void {
    this.plan.clearLayers();
    this.photos.clearLayers();
    this.clearMosaic();
  }

  destroy(): void {
    this.finished.destroy();
    this.clearMosaic();
    this.area.remove();
    this.plan.remove();
    this.photos.remove();
  }
}
