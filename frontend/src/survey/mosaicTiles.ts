// A survey mosaic's tiles as a Leaflet layer: the live one the survey panel follows and
// the finished ones listed by the hub share how their URL, zooms and bounds are read.
import * as L from "leaflet";

import type { MosaicDetail } from "./api";

/** The tile URL template, `revision` in it so each new photo has Leaflet ask again (the
 *  hub answers unchanged tiles with a 304); the hub's URL is from its root, the dashboard
 *  may be served below a path prefix. */
export function mosaicUrl(mosaic: MosaicDetail): string {
  const base = new URL(".", document.baseURI).pathname + mosaic.tile_url.replace(/^\//, "");
  return `${base}?v=${mosaic.revision ?? 0}`;
}

export function mosaicBounds(mosaic: MosaicDetail): L.LatLngBounds | undefined {
  const b = mosaic.bounds;
  return b ? L.latLngBounds([b[1], b[0]], [b[3], b[2]]) : undefined;
}

/** Zoom levels below the mosaic's coarsest tiles at which it is still drawn: further out,
 *  Leaflet would walk every coarsest tile under the view (a world view at zoom 2 over
 *  zoom-15 tiles is a billion of them, and the page hangs). */
const ZOOMS_BELOW_COARSEST = 4;

/** The mosaic above the base maps, or null while it has no tiles (no zoom yet). */
export function mosaicLayer(map: L.Map, mosaic: MosaicDetail): L.TileLayer | null {
  if (mosaic.max_zoom === null || mosaic.max_zoom === undefined) return null;
  return L.tileLayer(mosaicUrl(mosaic), {
    className: "survey-mosaic",
    maxZoom: Math.max(map.getMaxZoom(), mosaic.max_zoom),
    maxNativeZoom: mosaic.max_zoom,
    minNativeZoom: mosaic.min_zoom ?? undefined,
    minZoom: Math.max(0, (mosaic.min_zoom ?? mosaic.max_zoom) - ZOOMS_BELOW_COARSEST),
    bounds: mosaicBounds(mosaic),
    zIndex: 10, // above the base maps' tiles
  });
}
