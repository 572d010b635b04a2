// One vehicle on the map: a heading arrow with the vehicle id beside it.
// The marker element is `<div class="vehicle-marker" data-vehicle-id="...">`.
import * as L from "leaflet";
import { linkState } from "./format";
import type { VehicleSummary } from "./types";

const SVG_NS = "http://www.w3.org/2000/svg";
export const ICON_SIZE = 28;

function svgElement<K extends keyof SVGElementTagNameMap>(
  tag: K,
  attributes: Record<string, string>,
): SVGElementTagNameMap[K] {
  const element = document.createElementNS(SVG_NS, tag);
  for (const [name, value] of Object.entries(attributes)) element.setAttribute(name, value);
  return element;
}

/** The heading arrow (and the dot shown instead when there is no heading); also used by the replay. */
export function vehicleSymbol(): SVGSVGElement {
  const symbol = svgElement("svg", {
    class: "vehicle-symbol",
    viewBox: "0 0 28 28",
    width: String(ICON_SIZE),
    height: String(ICON_SIZE),
    "aria-hidden": "true",
  });
  symbol.append(
    svgElement("path", { class: "vehicle-arrow", d: "M14 2 L24 25 L14 19.5 L4 25 Z" }),
    svgElement("circle", { class: "vehicle-dot", cx: "14", cy: "14", r: "7" }),
  );
  return symbol;
}

export class VehicleMarker {
  readonly marker: L.Marker;
  private readonly content: HTMLDivElement;
  private readonly symbol: SVGSVGElement;
  private lastHeading: number | null | undefined = undefined; // undefined: never drawn

  constructor(
    readonly id: string,
    position: L.LatLngExpression,
    onClick: (id: string) => void,
  ) {
    this.content = document.createElement("div");
    this.content.className = "vehicle-marker-body";

    this.symbol = vehicleSymbol();

    const label = document.createElement("span");
    label.className = "vehicle-label";
    label.textContent = id;
    this.content.append(this.symbol, label);

    const icon = L.divIcon({
      className: "vehicle-marker",
      html: this.content,
      iconSize: [ICON_SIZE, ICON_SIZE],
      iconAnchor: [ICON_SIZE / 2, ICON_SIZE / 2],
    });
    // Leaflet creates the element lazily (and again if the marker is re-added).
    const createIcon = icon.createIcon.bind(icon);
    icon.createIcon = (oldIcon?: HTMLElement) => {
      const element = createIcon(oldIcon);
      element.dataset.vehicleId = id;
      return element;
    };

    this.marker = L.marker(position, { icon, keyboard: true, title: id, riseOnHover: true });
    this.marker.on("click", () => onClick(id));
  }

  update(vehicle: VehicleSummary, position: L.LatLngExpression): void {
    this.marker.setLatLng(position);
    const state = vehicle.state;
    const heading = state?.heading_deg ?? null;
    if (heading !== this.lastHeading) {
      this.lastHeading = heading;
      this.symbol.style.transform = heading === null ? "" : `rotate(${heading}deg)`;
      this.content.classList.toggle("no-heading", heading === null);
    }
    const link = linkState(vehicle);
    this.content.classList.toggle("offline", link !== "online");
    this.content.classList.toggle("armed", Boolean(state?.armed));
  }

  setSelected(selected: boolean): void {
    this.content.classList.toggle("selected", selected);
    this.marker.setZIndexOffset(selected ? 1000 : 0);
  }
}
