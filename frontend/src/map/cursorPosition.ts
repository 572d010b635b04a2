// The latitude and longitude under the pointer, above the map's attribution, as Mission
// Planner shows them: an operator reads a point off the map (to say it over the radio, or
// to type it into a mission) without placing anything. Hidden when the pointer leaves
// the map, and on touch screens, which have no hover.
import * as L from "leaflet";

const DECIMALS = 6; // about 0.1 m: finer than any fix this map draws

export function formatLatLon(at: L.LatLng): string {
  return `${at.lat.toFixed(DECIMALS)}, ${L.Util.wrapNum(at.lng, [-180, 180], true).toFixed(DECIMALS)}`;
}

export class CursorPosition extends L.Control {
  private readout: HTMLDivElement | null = null;

  constructor() {
    super({ position: "bottomright" });
  }

  onAdd(map: L.Map): HTMLElement {
    const readout = L.DomUtil.create("div", "cursor-position");
    readout.dataset.field = "cursor-position";
    readout.title = "Latitude, longitude under the pointer";
    readout.hidden = true;
    this.readout = readout;
    map.on("mousemove", this.show, this);
    map.on("mouseout", this.hide, this);
    return readout;
  }

  onRemove(map: L.Map): void {
    map.off("mousemove", this.show, this);
    map.off("mouseout", this.hide, this);
    this.readout = null;
  }

  private show(event: L.LeafletEvent): void {
    if (!this.readout) return;
    this.readout.hidden = false;
    this.readout.textContent = formatLatLon((event as L.LeafletMouseEvent).latlng);
  }

  private hide(): void {
    if (this.readout) this.readout.hidden = true;
  }
}
