// The event feed: a list of events with a vehicle and a severity filter, newest on top.
// The same view serves the live dashboard and the flight replay (where `showUntil`
// hides what had not yet happened at the replay's time). All vehicle text goes in with
// textContent: a STATUSTEXT is 50 bytes from a radio link, never markup.
import { element } from "../ui/dom";
import { type LogEvent, SEVERITY_NAMES, effectiveSeverity, severityName } from "./eventLog";

/** Rows kept in the DOM; the log itself holds more. */
const MAX_ROWS = 300;
const ALL = "";

export interface EventFeedOptions {
  /** Title of the panel, e.g. "Events". */
  title: string;
  /** Offer the vehicle filter (the replay shows one vehicle). */
  vehicleFilter: boolean;
  /** `data-feed` on the element, for tests and styles. */
  name: string;
}

function formatTime(unixSeconds: number): string {
  return new Date(unixSeconds * 1000).toLocaleTimeString([], { hour12: false });
}

export class EventFeed {
  readonly element: HTMLElement;
  private readonly list: HTMLOListElement;
  private readonly vehicleSelect: HTMLSelectElement | null = null;
  private readonly severitySelect: HTMLSelectElement;
  private readonly empty: HTMLElement;
  private events: readonly LogEvent[] = [];
  private until = Number.POSITIVE_INFINITY;
  private readonly vehicles = new Set<string>();

  constructor(options: EventFeedOptions) {
    this.list = element("ol", { className: "event-list" });
    this.list.setAttribute("aria-live", "polite");
    this.list.setAttribute("aria-relevant", "additions");
    this.empty = element("p", { className: "event-empty", textContent: "No events yet." });

    const filters = element("div", { className: "event-filters" });
    if (options.vehicleFilter) {
      this.vehicleSelect = element("select", { className: "event-filter" });
      this.vehicleSelect.dataset.field = "event-vehicle-filter";
      this.vehicleSelect.setAttribute("aria-label", "Show events of");
      this.vehicleSelect.append(new Option("All vehicles", ALL));
      this.vehicleSelect.addEventListener("change", () => this.render());
      filters.append(this.vehicleSelect);
    }
    this.severitySelect = element("select", { className: "event-filter" });
    this.severitySelect.dataset.field = "event-severity-filter";
    this.severitySelect.setAttribute("aria-label", "Least severe shown");
    for (const [value, name] of SEVERITY_NAMES.entries()) {
      const label = value === SEVERITY_NAMES.length - 1 ? "All severities" : `${name} and worse`;
      this.severitySelect.append(new Option(label, String(value)));
    }
    this.severitySelect.value = "6"; // info and worse: debug texts are noise in flight
    this.severitySelect.addEventListener("change", () => this.render());
    filters.append(this.severitySelect);

    this.element = element(
      "section",
      { className: "event-feed" },
      element("h2", { className: "panel-title", textContent: options.title }),
      filters,
      this.empty,
      this.list,
    );
    this.element.dataset.feed = options.name;
  }

  /** The events to show (the log's, oldest first); re-renders. */
  setEvents(events: readonly LogEvent[]): void {
    this.events = events;
    this.offerVehicles(events.map((event) => event.vehicleId));
    this.render();
  }

  /** Vehicles the filter offers even before they have an event: the whole fleet. */
  offerVehicles(ids: Iterable<string>): void {
    const before = this.vehicles.size;
    for (const id of ids) this.vehicles.add(id);
    if (this.vehicles.size !== before) this.refreshVehicleOptions();
  }

  /** Shows the vehicle's events only (null: all). */
  filterVehicle(vehicleId: string | null): void {
    if (!this.vehicleSelect) return;
    if (vehicleId && !this.vehicles.has(vehicleId)) {
      this.vehicles.add(vehicleId);
      this.refreshVehicleOptions();
    }
    this.vehicleSelect.value = vehicleId ?? ALL;
    this.render();
  }

  /** Replay: only what had happened by `unixSeconds`. */
  showUntil(unixSeconds: number): void {
    if (unixSeconds === this.until) return;
    this.until = unixSeconds;
    this.render();
  }

  private refreshVehicleOptions(): void {
    const select = this.vehicleSelect;
    if (!select) return;
    const current = select.value;
    const ids = [...this.vehicles].sort(new Intl.Collator(undefined, { numeric: true }).compare);
    select.replaceChildren(new Option("All vehicles", ALL), ...ids.map((id) => new Option(id, id)));
    select.value = current;
  }

  private render(): void {
    const vehicle = this.vehicleSelect?.value ?? ALL;
    const worst = Number(this.severitySelect.value);
    const rows: HTMLLIElement[] = [];
    for (let i = this.events.length - 1; i >= 0 && rows.length < MAX_ROWS; i--) {
      const event = this.events[i];
      if (event.time > this.until) continue;
      if (vehicle !== ALL && event.vehicleId !== vehicle) continue;
      if (effectiveSeverity(event) > worst) continue;
      rows.push(this.row(event));
    }
    this.list.replaceChildren(...rows);
    this.empty.hidden = rows.length > 0;
  }

  private row(event: LogEvent): HTMLLIElement {
    const severity = effectiveSeverity(event);
    const li = element("li", { className: "event" });
    li.dataset.eventId = String(event.id);
    li.dataset.vehicleId = event.vehicleId;
    li.dataset.kind = event.kind;
    li.dataset.category = event.category;
    li.dataset.severity = String(severity);
    const time = element("time", { className: "event-time", textContent: formatTime(event.time) });
    time.dateTime = new Date(event.time * 1000).toISOString();
    const who = element("span", { className: "event-vehicle", textContent: event.vehicleId });
    const level = element("span", { className: "event-severity", textContent: severityName(event.severity) });
    const text = element("span", { className: "event-text", textContent: event.text || event.kind });
    text.title = `${event.kind}: ${event.text}`;
    li.append(time, who, level, text);
    if (event.repeat > 1) li.append(element("span", { className: "event-repeat", textContent: `×${event.repeat}` }));
    return li;
  }
}
