// The replay on the map: the flight's whole track, a marker per logged event and
// the replay marker (the live markers' arrow, in the replay's colour) that moves
// along the track. The replay marker's element is
// `<div class="replay-marker" data-lat data-lon data-heading>`.
import * as L from "leaflet";
import { formatAuditTime } from "../audit/auditPanel";
import { element } from "../ui/dom";
import type { FlightTrack, ReplayPoint } from "./replayTrack";
import type { FlightEvent } from "../hub/types";
import { ICON_SIZE, vehicleSymbol } from "../map/vehicleMarker";

const FIT_MAX_ZOOM = 18;

/** A colour class for an event: by kind, and by MAVLink severity for status texts. */
export function eventTone(event: Pick<FlightEvent, "kind" | "severity">): "danger" | "warn" | "ok" | "info" | "muted" {
  if (event.kind === "failsafe" || event.kind === "id_clash") return "danger";
  if (event.kind === "link_down") return "warn";
  if (event.kind === "link_up") return "ok";
  if (event.kind === "mode" || event.kind === "armed" || event.kind === "disarmed") return "info";
  const severity = event.severity;
  if (severity === null || severity === undefined) return "muted";
  if (severity <= 3) return "danger"; // emergency, alert, critical, error
  if (severity === 4) return "warn"; // warning
  if (severity <= 6) return "info"; // notice, info
  return "muted"; // debug
}

const TONE_COLOURS: Record<ReturnType<typeof eventTone>, string> = {
  danger: "#ff6b5e",
  warn: "#f5b942",
  ok: "#3ecf8e",
  info: "#4fb3ff",
  muted: "#8796a8",
};

export class ReplayLayer {
  private readonly group = L.layerGroup();
  private readonly marker: L.Marker;
  private readonly content: HTMLDivElement;
  private readonly symbol: SVGSVGElement;
  private readonly label: HTMLSpanElement;
  private track: L.Polyline | null = null;
  private lastHeading: number | null | undefined = undefined;

  constructor(
    private readonly map: L.Map,
    private readonly onSeek: (t: number) => void,
  ) {
    this.content = document.createElement("div");
    this.content.className = "replay-marker-body";
    this.symbol = vehicleSymbol();
    this.label = document.createElement("span");
    this.label.className = "vehicle-label";
    this.content.append(this.symbol, this.label);
    const icon = L.divIcon({
      className: "replay-marker",
      html: this.content,
      iconSize: [ICON_SIZE, ICON_SIZE],
      iconAnchor: [ICON_SIZE / 2, ICON_SIZE / 2],
    });
    this.marker = L.marker([0, 0], { icon, keyboard: false, interactive: false, zIndexOffset: 2000 });
  }

  /** Draws a flight (replacing the one shown) and zooms the map to it. */
  show(track: FlightTrack, events: FlightEvent[]): void {
    this.clear();
    this.label.textContent = `${track.flight.vehicle_id} · replay`;
    const latLngs = track.points.map((point) => L.latLng(point.lat, point.lon));
    if (latLngs.length > 0) {
      this.track = L.polyline(latLngs, { className: "replay-track", color: "#f5d76e", weight: 3, opacity: 0.9 });
      this.group.addLayer(this.track);
    }
    for (const event of events) this.addEvent(track, event);
    this.group.addTo(this.map);
    this.fit();
  }

  /** Moves the replay marker; pans when it would leave the view. */
  moveTo(point: ReplayPoint | null, follow: boolean): void {
    if (!point) {
      this.marker.remove();
      return;
    }
    const position = L.latLng(point.lat, point.lon);
    this.marker.setLatLng(position);
    if (!this.group.hasLayer(this.marker)) this.group.addLayer(this.marker);
    const element = this.marker.getElement();
    if (element) {
      element.dataset.lat = point.lat.toFixed(7);
      element.dataset.lon = point.lon.toFixed(7);
      element.dataset.heading = point.heading === null ? "" : point.heading.toFixed(1);
    }
    if (point.heading !== this.lastHeading) {
      this.lastHeading = point.heading;
      this.symbol.style.transform = point.heading === null ? "" : `rotate(${point.heading}deg)`;
      this.content.classList.toggle("no-heading", point.heading === null);
    }
    if (follow && !this.map.getBounds().pad(-0.1).contains(position)) {
      this.map.panTo(position, { animate: false });
    }
  }

  fit(): void {
    const bounds = this.track?.getBounds();
    if (!bounds || !bounds.isValid()) return;
    const maxZoom = Math.min(FIT_MAX_ZOOM, this.map.getMaxZoom());
    this.map.fitBounds(bounds, { padding: [40, 40], maxZoom, animate: false });
  }

  clear(): void {
    this.group.clearLayers();
    this.group.remove();
    this.track = null;
    this.lastHeading = undefined;
  }

  private addEvent(track: FlightTrack, event: FlightEvent): void {
    const t = track.clamp(event.time - track.origin);
    const where = track.positionAt(t);
    if (!where) return;
    const tone = eventTone(event);
    const marker = L.circleMarker([where.lat, where.lon], {
      className: `event-marker event-${tone}`,
      radius: 6,
      color: "#0b1016",
      weight: 1.5,
      fillColor: TONE_COLOURS[tone],
      fillOpacity: 0.95,
    });
    // An element, never a string: Leaflet puts a string tooltip in as HTML, and an event's
    // text comes from the vehicle (a STATUSTEXT any MAVLink peer can send).
    const tooltip = element("span", {
      className: "event-tooltip",
      textContent: `${formatAuditTime(event.time)} · ${event.text || event.kind}`,
    });
    marker.bindTooltip(tooltip, { direction: "top" });
    marker.on("click", () => this.onSeek(t));
    marker.on("add", () => {
      const element = marker.getElement() as SVGElement | undefined;
      if (!element) return;
      element.dataset.eventId = String(event.id);
      element.dataset.kind = event.kind;
      if (event.severity !== null) element.dataset.severity = String(event.severity);
    });
    this.group.addLayer(marker);
  }
}
