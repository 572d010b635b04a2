// The base maps and the layer switcher: the hub's configured online street map and
// imagery, its offline tile sets (GET /api/v1/tiles, served at /tiles/<name>/...), and
// a plain grid. The first available is shown; an online map whose tiles all fail gives
// way to the first offline set, and with nothing to show the map says so in one line.
import * as L from "leaflet";
import { fetchTileSets } from "./tileSets";
import type { TileSet } from "./tileSets";
import type { HubConfig } from "../hub/types";
import { icon } from "../ui/icons";

const FAILURES_BEFORE_FALLBACK = 4;
const MAX_ZOOM = 22;
export const GRID_NAME = "Grid (no tiles)";

function escapeText(text: string): string {
  const span = document.createElement("span");
  span.textContent = text;
  return span.innerHTML.replace(/"/g, "&quot;");
}

export interface BaseMapsOptions {
  /** Shows or hides the CSS grid behind a map without tiles. */
  setGrid(shown: boolean): void;
  /** Overlays for the switcher's check boxes (e.g. the trails). */
  overlays: Record<string, L.Layer>;
}

interface Base {
  name: string;
  layer: L.Layer;
  online: boolean;
}

export class BaseMaps {
  private readonly notice: HTMLDivElement;
  private readonly noticeControl: L.Control;
  private readonly noticeText: HTMLElement;
  private bases: Base[] = [];
  private control: L.Control.Layers | null = null;
  private destroyed = false;
  private current: Base | null = null;

  constructor(
    private readonly map: L.Map,
    private readonly config: HubConfig,
    private readonly options: BaseMapsOptions,
  ) {
    this.notice = L.DomUtil.create("div", "map-notice");
    this.notice.dataset.field = "basemap-notice";
    this.notice.hidden = true;
    // One line (its full text on hover) with a button that puts it away, so it never
    // stands over a panel's buttons for good; a new notice shows again.
    this.noticeText = L.DomUtil.create("span", "map-notice-text", this.notice);
    const dismiss = L.DomUtil.create("button", "map-notice-dismiss", this.notice);
    dismiss.type = "button";
    dismiss.dataset.action = "dismiss-basemap-notice";
    dismiss.title = "Hide this notice";
    dismiss.setAttribute("aria-label", dismiss.title);
    dismiss.append(icon("close"));
    dismiss.addEventListener("click", () => (this.notice.hidden = true));
    L.DomEvent.disableClickPropagation(this.notice);
    const NoticeControl = L.Control.extend({ onAdd: () => this.notice });
    this.noticeControl = new NoticeControl({ position: "bottomleft" });
    this.noticeControl.addTo(map);
    map.on("baselayerchange", (event) => this.chosen((event as L.LayersControlEvent).layer));
  }

  /** Builds the switcher; the offline sets come from the hub. */
  async start(): Promise<void> {
    const online: Base[] = [];
    const { config } = this;
    if (config.basemap_url) {
      online.push(this.online("Street map", config.basemap_url, config.basemap_attribution, config.basemap_max_zoom));
    }
    if (config.imagery_url) {
      online.push(
        this.online("Imagery", config.imagery_url, config.imagery_attribution ?? "", config.imagery_max_zoom ?? 19),
      );
    }
    let sets: TileSet[] = [];
    try {
      sets = await fetchTileSets();
    } catch {
      sets = []; // the list is a convenience: the online maps and the grid still work
    }
    // The session may have ended while the list was on its way: the map is gone then.
    if (this.destroyed) return;
    const offline = sets.map((set) => this.offline(set));
    const grid: Base = { name: GRID_NAME, layer: L.layerGroup(), online: false };
    this.bases = [...online, ...offline, grid];
    const layers: Record<string, L.Layer> = {};
    for (const base of this.bases) layers[base.name] = base.layer;
    this.control = L.control.layers(layers, this.options.overlays, { position: "topright" }).addTo(this.map);
    const first = this.bases[0];
    first.layer.addTo(this.map);
    this.chosen(first.layer);
  }

  /** The name of the base map shown now. */
  get shown(): string | null {
    return this.current?.name ?? null;
  }

  private online(name: string, url: string, attribution: string, maxNativeZoom: number): Base {
    const layer = L.tileLayer(url, {
      attribution,
      maxZoom: MAX_ZOOM,
      maxNativeZoom,
      // The hub sends no Referer anywhere; tile servers (OpenStreetMap's) ask for one.
      referrerPolicy: "strict-origin-when-cross-origin",
    });
    const base: Base = { name, layer, online: true };
    let loaded = 0;
    let failed = 0;
    layer.on("tileload", () => {
      loaded++;
      if (this.current === base) this.say("");
    });
    layer.on("tileerror", () => {
      failed++;
      if (loaded === 0 && failed === FAILURES_BEFORE_FALLBACK && this.current === base) this.unreachable(base);
    });
    return base;
  }

  private offline(set: TileSet): Base {
    const bounds = set.bounds
      ? L.latLngBounds([set.bounds[1], set.bounds[0]], [set.bounds[3], set.bounds[2]])
      : undefined;
    // The hub's URL is from its root; the dashboard may be served below a path prefix.
    const url = new URL(".", document.baseURI).pathname + set.url.replace(/^\//, "");
    const layer = L.tileLayer(url, {
      // From the file's metadata: shown as text, never as markup.
      attribution: escapeText(set.attribution || set.name),
      maxZoom: MAX_ZOOM,
      // No minNativeZoom: scaling a zoom-12 set up to a world view would have Leaflet
      // walk millions of tile addresses. Below the set's zooms it asks, gets a 404 once.
      maxNativeZoom: set.max_zoom,
      bounds,
    });
    return { name: set.name, layer, online: false };
  }

  private unreachable(base: Base): void {
    const fallback = this.bases.find((b) => !b.online && b.name !== GRID_NAME);
    if (fallback) {
      this.map.removeLayer(base.layer);
      fallback.layer.addTo(this.map);
      this.chosen(fallback.layer);
      this.say(`${base.name} is unreachable: showing the offline tile set "${fallback.name}".`);
    } else {
      this.say(
        `No base map: ${base.name.toLowerCase()} is unreachable and the hub has no offline tiles (add .mbtiles or .pmtiles files with \`gcs tiles import\`).`,
      );
      this.options.setGrid(true);
    }
  }

  private chosen(layer: L.Layer): void {
    const base = this.bases.find((b) => b.layer === layer);
    if (!base) return;
    this.current = base;
    this.map.getContainer().dataset.basemap = base.name;
    this.options.setGrid(base.name === GRID_NAME);
    if (base.name === GRID_NAME) {
      const others = this.bases.length > 1;
      this.say(
        others
          ? ""
          : "No base map: none is configured and the hub has no offline tiles (add .mbtiles or .pmtiles files with `gcs tiles import`).",
      );
    } else if (!base.online) {
      this.say("");
    }
  }

  private say(text: string): void {
    if (this.noticeText.textContent === text && text !== "") return; // dismissed stays dismissed
    this.noticeText.textContent = text;
    this.notice.title = text;
    this.notice.hidden = text === "";
  }

  destroy(): void {
    this.destroyed = true;
    this.control?.remove();
    this.noticeControl.remove();
  }
}
