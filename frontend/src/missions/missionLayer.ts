// A mission on the map: a numbered marker per item that has a place, the legs between
// them, take-off / land / RTL marked, the active item highlighted (MISSION_CURRENT) and the
// legs already flown dimmed. In edit mode the markers drag and a click on a leg inserts a
// waypoint there; the items the rails refuse, and the legs flown to them, turn red with
// the refusal as their tooltip.
//
// Plain Leaflet markers and polylines rather than Leaflet-Geoman: a mission is an ordered
// list of typed MAVLink items (a take-off or an RTL has no vertex, a loiter has a time),
// not a free polyline, so Geoman's vertex editing would need mapping back onto items
// anyway; draggable markers and clickable legs are all the editing it needs, with no
// extra dependency.
//
// A long mission (a survey's, 95 items) is drawn as its lanes: the path's lines, and
// numbers only where it starts, ends, turns, takes off, lands or returns, on the active
// item and on refused ones; a turn's number too close to one already drawn waits for the
// operator to zoom in (lanes.ts).
import * as L from "leaflet";
import { CMD, type MissionItem, placeOf } from "./model";
import { type PlacedItem, numberedItems } from "./lanes";

export interface MissionDrawing {
  items: readonly MissionItem[];
  /** Where the vehicle starts (and RTL returns to): its home, else its position. */
  home: L.LatLng | null;
  /** MISSION_CURRENT: the item being flown (1 is the first after home), null if none. */
  current: number | null;
  /** Refusals by item number (1 is the first after home). */
  refusals: Map<number, string[]>;
  /** Markers drag (a plan being edited). */
  editable: boolean;
  /** A click on a leg inserts a waypoint: only while adding waypoints is the map's tool. */
  inserting: boolean;
}

export interface MissionLayerHooks {
  /** An item's marker was dragged to a new place (index into items). */
  move(index: number, to: L.LatLng): void;
  /** A leg was clicked in edit mode: insert a waypoint before item `index`. */
  insert(index: number, at: L.LatLng): void;
  pick(index: number): void;
}

function label(item: MissionItem, seq: number): string {
  switch (item.command) {
    case CMD.TAKEOFF:
      return `${seq} ↑`;
    case CMD.LAND:
      return `${seq} L`;
    case CMD.RTL:
      return `${seq} R`;
    default:
      return String(seq);
  }
}

const KIND: Record<number, string> = {
  [CMD.TAKEOFF]: "takeoff",
  [CMD.LAND]: "land",
  [CMD.RTL]: "rtl",
  [CMD.LOITER_TIME]: "loiter",
};

export class MissionLayer {
  private readonly group = L.layerGroup();

  constructor(
    private readonly map: L.Map,
    private readonly hooks: MissionLayerHooks,
  ) {
    this.group.addTo(map);
    map.on("zoomend", this.redraw);
  }

  private last: MissionDrawing | null = null;
  private readonly redraw = (): void => {
    if (this.last) this.draw(this.last);
  };

  clear(): void {
    this.last = null;
    this.group.clearLayers();
  }

  draw(drawing: MissionDrawing): void {
    this.group.clearLayers();
    this.last = drawing;
    const { items, home, current, refusals, editable, inserting } = drawing;
    const placed: PlacedItem[] = [];
    let previous: L.LatLng | null = home;
    items.forEach((item, index) => {
      const seq = index + 1;
      const place = placeOf(item);
      // A take-off climbs where the vehicle stands; an RTL flies back to home.
      let at: L.LatLng | null = place ? L.latLng(place[0], place[1]) : null;
      if (!at && (item.command === CMD.TAKEOFF || item.command === CMD.RTL)) at = home;
      if (!at && item.command === CMD.LAND) at = previous; // lands where it is
      if (!at) return;
      const refused = refusals.get(seq);
      const flown = current !== null && seq < current;
      const active = current !== null && seq === current;
      if (previous && !(previous.equals(at) && item.command !== CMD.RTL)) {
        this.addLeg(previous, at, index, {
          refused: Boolean(refused),
          flown,
          active,
          editable: inserting,
          rtl: item.command === CMD.RTL,
        });
      }
      placed.push({ item, seq, at, key: Boolean(refused) || active, movable: place !== null });
      previous = at;
    });
    const numbered = numberedItems(placed, (at) => this.map.latLngToLayerPoint(at));
    for (const { item, seq, at, movable } of placed) {
      if (!numbered.has(seq)) continue;
      const refused = refusals.get(seq);
      const flown = current !== null && seq < current;
      const active = current !== null && seq === current;
      this.addMarker(item, seq, seq - 1, at, { refused, flown, active, editable, movable });
    }
    // How many of the places carry a number: for the tests and for a person reading the DOM.
    this.map.getContainer().dataset.missionNumbered = `${numbered.size}/${placed.length}`;
  }

  destroy(): void {
    this.map.off("zoomend", this.redraw);
    this.group.remove();
  }

  private addLeg(
    from: L.LatLng,
    to: L.LatLng,
    index: number,
    state: { refused: boolean; flown: boolean; active: boolean; editable: boolean; rtl: boolean },
  ): void {
    const classes = ["mission-leg"];
    if (state.refused) classes.push("refused");
    if (state.flown) classes.push("flown");
    if (state.active) classes.push("active");
    if (state.rtl) classes.push("rtl");
    const leg = L.polyline([from, to], {
      className: classes.join(" "),
      weight: 4,
      dashArray: state.rtl ? "6 6" : undefined,
      interactive: state.editable,
      bubblingMouseEvents: false,
    });
    leg.on("add", () => {
      const element = leg.getElement();
      if (element instanceof SVGElement) element.dataset.seq = String(index + 1);
    });
    if (state.editable) {
      leg.on("click", (event: L.LeafletMouseEvent) => {
        L.DomEvent.stop(event);
        this.hooks.insert(index, event.latlng);
      });
      const hint = document.createElement("span");
      hint.textContent = "Click to insert a waypoint";
      leg.bindTooltip(hint, { sticky: true });
    }
    this.group.addLayer(leg);
  }

  private addMarker(
    item: MissionItem,
    seq: number,
    index: number,
    at: L.LatLng,
    state: { refused?: string[]; flown: boolean; active: boolean; editable: boolean; movable: boolean },
  ): void {
    const element = document.createElement("div");
    element.className = "mission-item-body";
    element.textContent = label(item, seq);
    const icon = L.divIcon({ className: "mission-item", html: element, iconSize: [26, 26], iconAnchor: [13, 13] });
    const createIcon = icon.createIcon.bind(icon);
    icon.createIcon = (old?: HTMLElement) => {
      const created = createIcon(old);
      created.dataset.seq = String(seq);
      created.dataset.kind = KIND[item.command] ?? "waypoint";
      created.classList.toggle("refused", Boolean(state.refused));
      created.classList.toggle("flown", state.flown);
      created.classList.toggle("active", state.active);
      if (state.refused) created.title = state.refused.join("\n");
      return created;
    };
    const marker = L.marker(at, {
      icon,
      draggable: state.editable && state.movable,
      keyboard: false,
      zIndexOffset: state.active ? 500 : 0,
      bubblingMouseEvents: false,
    });
    marker.on("dragend", () => this.hooks.move(index, marker.getLatLng()));
    marker.on("click", (event: L.LeafletMouseEvent) => {
      L.DomEvent.stop(event);
      this.hooks.pick(index);
    });
    this.group.addLayer(marker);
    if (state.refused) {
      // Text, never HTML: the messages quote the hub.
      const tip = document.createElement("div");
      for (const line of state.refused) tip.append(Object.assign(document.createElement("div"), { textContent: line }));
      marker.bindTooltip(tip, { direction: "top", className: "mission-refusal" });
    }
  }

  /** The Leaflet map, for the editor's clicks. */
  get leaflet(): L.Map {
    return this.map;
  }
}
