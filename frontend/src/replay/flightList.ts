// The stored flights, newest first, a page at a time ("Load older" asks for the
// flights before the hub's `next_before_id`), optionally of one vehicle only.
import { fetchFlights } from "../hub/api";
import { formatAuditTime } from "../audit/auditPanel";
import { actionButton, element, field } from "../ui/dom";
import { MISSING } from "../ui/format";
import { Pager } from "../ui/pager";
import { formatClock } from "./replayTrack";
import type { Flight } from "../hub/types";

const PAGE_SIZE = 50;
const COLUMNS = [
  { key: "vehicle", title: "Vehicle" },
  { key: "start", title: "Start" },
  { key: "duration", title: "Duration" },
  { key: "distance", title: "Distance" },
  { key: "max_alt", title: "Max alt" },
  { key: "battery_used", title: "Battery used" },
] as const;
type Column = (typeof COLUMNS)[number]["key"];

function number(value: number | null | undefined): value is number {
  return value !== null && value !== undefined && Number.isFinite(value);
}

export function formatDistance(metres: number | null | undefined): string {
  if (!number(metres)) return MISSING;
  return metres < 1000 ? `${Math.round(metres)} m` : `${(metres / 1000).toFixed(2)} km`;
}

export function flightCells(flight: Flight): Record<Column, string> {
  const duration = number(flight.duration_s)
    ? flight.duration_s
    : flight.end_time !== null
      ? flight.end_time - flight.start_time
      : null;
  return {
    vehicle: flight.vehicle_id,
    start: formatAuditTime(flight.start_time),
    duration: flight.end_time === null ? "in flight" : number(duration) ? formatClock(duration) : MISSING,
    distance: formatDistance(flight.distance_m),
    max_alt: number(flight.max_alt_m) ? `${flight.max_alt_m.toFixed(1)} m` : MISSING,
    battery_used: number(flight.battery_used_pct) ? `${Math.round(flight.battery_used_pct)} %` : MISSING,
  };
}

export class FlightList {
  readonly element: HTMLElement;
  private readonly body: HTMLTableSectionElement;
  private readonly vehicleFilter: HTMLInputElement;
  private readonly vehicleChoices: HTMLDataListElement;
  private readonly pager: Pager<Flight>;
  private readonly rows = new Map<number, HTMLTableRowElement>();
  private readonly flights = new WeakMap<HTMLTableRowElement, Flight>();
  /** The vehicle of the list on show, so "Load older" pages the same query. */
  private vehicleId: string | undefined;
  private selectedId: number | null = null;

  constructor(private readonly onPick: (flight: Flight) => void) {
    this.vehicleChoices = element("datalist", { id: "flight-vehicles" });
    this.vehicleFilter = element("input", {
      name: "vehicle",
      type: "search",
      placeholder: "all vehicles",
      autocomplete: "off",
      spellcheck: false,
    });
    this.vehicleFilter.dataset.field = "flight-vehicle";
    this.vehicleFilter.setAttribute("list", this.vehicleChoices.id);
    this.vehicleFilter.addEventListener("change", () => {
      if ((this.vehicleFilter.value.trim() || undefined) !== this.vehicleId) void this.refresh();
    });
    const refreshButton = actionButton("flights-refresh", "Refresh", () => void this.refresh());
    const filters = element(
      "form",
      { className: "flight-filters" },
      element("label", {}, "Vehicle ", this.vehicleFilter),
      this.vehicleChoices,
      refreshButton,
    );
    filters.addEventListener("submit", (event) => {
      event.preventDefault();
      // Enter also fires "change", which may have started this very refresh.
      if (!this.pager.loading) void this.refresh();
    });

    const head = element("tr");
    for (const { title } of COLUMNS) head.append(element("th", { scope: "col", textContent: title }));
    this.body = element("tbody");
    this.body.addEventListener("click", (event) => this.pickFrom(event.target));
    this.body.addEventListener("keydown", (event) => {
      if (event.key === "Enter" || event.key === " ") {
        event.preventDefault();
        this.pickFrom(event.target);
      }
    });
    const table = element("table", { className: "flight-table" }, element("thead", {}, head), this.body);

    const status = field("p", "flights-status", { className: "panel-status" });
    status.setAttribute("role", "status");
    const moreButton = actionButton("flights-more", "Load older", () => void this.pager.loadOlder());
    moreButton.hidden = true;

    this.element = element(
      "section",
      { className: "flight-list" },
      filters,
      element("div", { className: "flight-scroll" }, table, status, moreButton),
    );
    this.element.setAttribute("aria-label", "Stored flights");

    this.pager = new Pager<Flight>({
      fetch: async (beforeId) => {
        const page = await fetchFlights({ limit: PAGE_SIZE, vehicleId: this.vehicleId, beforeId });
        return { items: page.flights, nextBeforeId: page.next_before_id ?? null };
      },
      clear: () => {
        this.body.replaceChildren();
        this.rows.clear();
      },
      show: (flights) => this.show(flights),
      describe: (more) => {
        const shown = this.rows.size;
        if (shown === 0) {
          return this.vehicleId ? `No stored flights of ${this.vehicleId}.` : "No stored flights yet.";
        }
        return more ? "" : `${shown} ${shown === 1 ? "flight" : "flights"}; that is all.`;
      },
      describeError: (message) => `Could not load the flights: ${message}`,
      status,
      moreButton,
      refreshButton,
      busy: this.element,
    });
  }

  /** Offers these vehicle ids in the filter's suggestions. */
  suggestVehicles(ids: Iterable<string>): void {
    const known = new Set([...this.vehicleChoices.options].map((option) => option.value));
    for (const id of ids) {
      if (known.has(id)) continue;
      known.add(id);
      this.vehicleChoices.append(element("option", { value: id }));
    }
  }

  /** Marks a row as the flight on show. */
  select(id: number | null): void {
    if (this.selectedId !== null) this.rows.get(this.selectedId)?.classList.remove("selected");
    this.selectedId = id;
    const row = id !== null ? this.rows.get(id) : undefined;
    row?.classList.add("selected");
    row?.setAttribute("aria-selected", "true");
  }

  /** Reloads the newest page with the current filter. */
  async refresh(): Promise<void> {
    this.vehicleId = this.vehicleFilter.value.trim() || undefined;
    await this.pager.refresh();
  }

  private show(flights: Flight[]): void {
    for (const flight of flights) {
      if (this.rows.has(flight.id)) continue;
      const row = this.row(flight);
      this.rows.set(flight.id, row);
      this.body.append(row);
    }
    this.suggestVehicles(flights.map((flight) => flight.vehicle_id));
    this.select(this.selectedId);
  }

  private pickFrom(target: EventTarget | null): void {
    const row = (target as HTMLElement | null)?.closest<HTMLTableRowElement>("tr[data-flight-id]");
    const flight = row ? this.flights.get(row) : undefined;
    if (flight) this.onPick(flight);
  }

  private row(flight: Flight): HTMLTableRowElement {
    const tr = element("tr", { className: "flight-row", tabIndex: 0 });
    tr.dataset.flightId = String(flight.id);
    tr.dataset.state = flight.end_time === null ? "open" : "closed";
    const values = flightCells(flight);
    for (const { key } of COLUMNS) {
      const td = element("td", { textContent: values[key], title: values[key] });
      td.dataset.field = key;
      tr.append(td);
    }
    tr.cells[1].title = new Date(flight.start_time * 1000).toISOString();
    this.flights.set(tr, flight);
    return tr;
  }
}
