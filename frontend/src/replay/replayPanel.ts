// The "Flights" mode: the stored flights on the right, and the chosen one replayed
// on the map (track, events, a moving marker) with a timeline, the values at the
// replay position, small charts and export links.
//
// The replay clock counts seconds since the start of the flight: the scrubber's
// value, the charts' x axis and the time display all use it. Playback advances it
// by (real time elapsed × speed) each animation frame, and the marker's position
// and heading are interpolated between the samples around it.
import { formatAuditTime } from "../audit/auditPanel";
import { actionButton, element, field, setText } from "../ui/dom";
import { FlightList } from "./flightList";
import { MISSING, formatAltitude, formatSpeed } from "../ui/format";
import type { FleetMap } from "../map/fleetMap";
import type { DashboardStore } from "../store/dashboardStore";
import { ReplayCharts } from "./replayCharts";
import { ReplayLayer, eventTone } from "./replayMap";
import { ReplayScans } from "./replayScans";
import { EventFeed } from "../events/eventFeed";
import { EventLog } from "../events/eventLog";
import { FlightTrack, formatClock, type ReplayState } from "./replayTrack";
import type { Flight, FlightEvent } from "../hub/types";
import { EXPORTS, type LoadedFlight, loadFlight } from "./flightData";

export const REPLAY_SPEEDS = [1, 2, 5, 10, 30] as const;
/** A frame later than this (a background tab) does not jump the replay ahead. */
const MAX_FRAME_S = 0.25;

type ReplayViewState = "empty" | "loading" | "ready" | "error";

function formatBatteryAt(state: ReplayState): string {
  const parts: string[] = [];
  if (state.batteryRemaining !== null) parts.push(`${Math.round(state.batteryRemaining)}%`);
  if (state.batteryVoltage !== null) parts.push(`${state.batteryVoltage.toFixed(1)} V`);
  return parts.length ? parts.join(" · ") : MISSING;
}

export class ReplayPanel {
  readonly element: HTMLElement;
  private readonly list: FlightList;
  private readonly layer: ReplayLayer;
  private readonly charts: ReplayCharts;
  private readonly scans: ReplayScans;

  private readonly view: HTMLElement;
  private readonly title: HTMLElement;
  private readonly status: HTMLElement;
  private readonly playButton: HTMLButtonElement;
  private readonly scrubber: HTMLInputElement;
  private readonly speedSelect: HTMLSelectElement;
  private readonly follow: HTMLInputElement;
  private readonly eventTicks: HTMLElement;
  private readonly values: Record<"time" | "at" | "alt" | "groundspeed" | "battery" | "mode", HTMLElement>;
  private readonly exportLinks: HTMLAnchorElement[] = [];
  /** The flight's events as the live feed shows them, up to the replay's time. */
  private readonly eventFeed = new EventFeed({ title: "Events", vehicleFilter: false, name: "replay" });

  private track: FlightTrack | null = null;
  private t = 0;
  private playing = false;
  private frame = 0;
  private lastFrameAt = 0;
  private scrubbing = false;
  /** Bumped by every flight load, so a slow answer cannot replace a newer flight. */
  private generation = 0;

  constructor(
    private readonly map: FleetMap,
    onClose: () => void,
    store: DashboardStore,
  ) {
    // New vehicles join the flight list's vehicle filter while it is open.
    store.subscribe((state) => state.fleet, ({ all }) => this.isOpen && this.list.suggestVehicles(all.keys()));
    this.list = new FlightList((flight) => void this.load(flight));
    this.layer = new ReplayLayer(map.leaflet, (t) => this.seek(t));
    this.charts = new ReplayCharts((t) => this.seek(t));
    this.scans = new ReplayScans(map.leaflet);

    this.title = element("h3", { className: "replay-title" });
    this.status = field("p", "replay-status", { className: "panel-status" });
    this.status.setAttribute("role", "status");

    this.playButton = actionButton("replay-play", "Play", () => this.togglePlay());
    this.playButton.classList.add("replay-play");
    this.playButton.setAttribute("aria-pressed", "false");

    this.scrubber = field("input", "replay-scrubber", { type: "range", min: "0", max: "0", step: "any", value: "0" });
    this.scrubber.className = "replay-scrubber";
    this.scrubber.setAttribute("aria-label", "Replay position, seconds since the start of the flight");
    this.scrubber.addEventListener("input", () => this.seek(this.scrubber.valueAsNumber));
    this.scrubber.addEventListener("pointerdown", () => (this.scrubbing = true));
    const endScrub = () => (this.scrubbing = false);
    this.scrubber.addEventListener("pointerup", endScrub);
    this.scrubber.addEventListener("pointercancel", endScrub);

    this.speedSelect = field("select", "replay-speed", { className: "replay-speed" });
    this.speedSelect.setAttribute("aria-label", "Replay speed");
    for (const speed of REPLAY_SPEEDS) {
      this.speedSelect.append(element("option", { value: String(speed), textContent: `${speed}×` }));
    }
    this.speedSelect.value = "1";

    this.follow = field("input", "replay-follow", { type: "checkbox", checked: true });

    this.eventTicks = element("div", { className: "replay-event-ticks" });
    this.eventTicks.setAttribute("aria-hidden", "true");

    this.values = {
      time: field("span", "replay-time", { className: "replay-time", textContent: "00:00:00 / 00:00:00" }),
      at: field("span", "replay-at"),
      alt: field("span", "replay-alt", { textContent: MISSING }),
      groundspeed: field("span", "replay-groundspeed", { textContent: MISSING }),
      battery: field("span", "replay-battery", { textContent: MISSING }),
      mode: field("span", "replay-mode", { textContent: MISSING }),
    };
    const value = (label: string, node: HTMLElement) =>
      element(
        "div",
        { className: "replay-value" },
        element("span", { className: "replay-value-label", textContent: label }),
        node,
      );

    const exports = element("div", { className: "replay-exports" }, element("span", { textContent: "Export " }));
    for (const { format, label, title } of EXPORTS) {
      const link = element("a", { className: "panel-button", textContent: label, title });
      link.dataset.action = `export-${format}`;
      this.exportLinks.push(link);
      exports.append(link);
    }

    this.view = element(
      "section",
      { className: "replay" },
      element("header", { className: "replay-heading" }, this.title, this.values.at),
      this.status,
      element(
        "div",
        { className: "replay-timeline" },
        this.playButton,
        element("div", { className: "replay-track-input" }, this.eventTicks, this.scrubber),
        this.values.time,
        element("label", { className: "replay-option" }, this.speedSelect),
        element(
          "label",
          { className: "replay-option", title: "Keep the replay marker in view" },
          this.follow,
          "Follow",
        ),
      ),
      element(
        "div",
        { className: "replay-values" },
        value("Alt", this.values.alt),
        value("Speed", this.values.groundspeed),
        value("Battery", this.values.battery),
        value("Mode", this.values.mode),
      ),
      this.charts.element,
      this.eventFeed.element,
      exports,
    );
    this.view.setAttribute("aria-label", "Flight replay");

    this.element = element(
      "aside",
      { id: "replay-panel", className: "replay-panel" },
      element(
        "header",
        { className: "panel-header" },
        element("h2", { textContent: "Flights" }),
        actionButton("close-flights", "Back to live", onClose),
      ),
      this.list.element,
      this.view,
    );
    this.element.setAttribute("aria-label", "Flights");
    this.element.hidden = true;
    this.setViewState("empty");
  }

  get isOpen(): boolean {
    return !this.element.hidden;
  }

  /** Enters the replay mode: the flight list, live markers de-emphasised. */
  open(vehicleIds: Iterable<string>): void {
    if (this.isOpen) return;
    this.element.hidden = false;
    this.map.setReplaying(true);
    this.list.suggestVehicles(vehicleIds);
    void this.list.refresh();
  }

  /** Leaves the replay mode and restores the live view. */
  close(): void {
    if (!this.isOpen) return;
    this.unload();
    this.element.hidden = true;
    this.map.setReplaying(false);
  }

  destroy(): void {
    this.unload();
    this.element.remove();
  }

  /** Loads a flight's samples and events and shows it at its start, paused. */
  async load(flight: Flight): Promise<void> {
    this.unload(); // bumps the generation
    const generation = this.generation;
    this.list.select(flight.id);
    this.element.dataset.flightId = String(flight.id);
    this.title.textContent = `${flight.vehicle_id} · ${formatAuditTime(flight.start_time)}`;
    for (const [index, { format, url }] of EXPORTS.entries()) {
      const link = this.exportLinks[index];
      link.href = url(flight.id);
      link.download = `flight-${flight.id}-${flight.vehicle_id}.${format}`;
    }
    this.setViewState("loading", "Loading the flight…");

    let loaded: LoadedFlight;
    try {
      loaded = await loadFlight(flight);
      if (generation !== this.generation) return;
    } catch (error) {
      if (generation !== this.generation) return;
      this.setViewState(
        "error",
        `Could not load flight ${flight.id}: ${error instanceof Error ? error.message : String(error)}`,
      );
      return;
    }
    const { track, events, eventsFailed } = loaded;

    this.track = track;
    this.scrubber.max = String(track.duration);
    const notes: string[] = [];
    if (track.isEmpty) notes.push("No telemetry was stored for this flight.");
    else if (track.points.length === 0) notes.push("No position was recorded in this flight.");
    if (flight.end_time === null) notes.push("Still flying: showing the samples so far.");
    if (eventsFailed) notes.push(`Events not loaded: ${eventsFailed}`);
    this.setViewState(track.isEmpty ? "error" : "ready", notes.join(" "));
    if (track.isEmpty) return;

    this.layer.show(track, events);
    this.scans.show(flight.vehicle_id);
    const log = new EventLog(Number.MAX_SAFE_INTEGER);
    log.add(events);
    this.eventFeed.setEvents(log.all);
    this.showEventTicks(track, events);
    this.charts.show(track);
    this.render(0);
  }

  // ------------------------------------------------------------- playback

  private togglePlay(): void {
    if (this.playing) this.pause();
    else this.play();
  }

  private play(): void {
    const track = this.track;
    if (!track || this.playing) return;
    if (this.t >= track.duration) this.render(0);
    this.playing = true;
    this.setPlayButton();
    this.lastFrameAt = performance.now();
    this.frame = requestAnimationFrame(this.tick);
  }

  private pause(): void {
    this.playing = false;
    cancelAnimationFrame(this.frame);
    this.frame = 0;
    this.setPlayButton();
  }

  private readonly tick = (now: number): void => {
    this.frame = 0;
    const track = this.track;
    if (!this.playing || !track) return;
    const elapsed = Math.min(Math.max(now - this.lastFrameAt, 0) / 1000, MAX_FRAME_S);
    this.lastFrameAt = now;
    const t = Math.min(this.t + elapsed * this.speed, track.duration);
    this.render(t);
    if (t >= track.duration) this.pause();
    else this.frame = requestAnimationFrame(this.tick);
  };

  private get speed(): number {
    const speed = Number(this.speedSelect.value);
    return Number.isFinite(speed) && speed > 0 ? speed : 1;
  }

  /** Jumps to `t` seconds since the flight's start (playing goes on from there). */
  seek(t: number): void {
    if (!this.track) return;
    this.render(this.track.clamp(t));
  }

  /** Shows the replay at `t`: marker, scrubber, values, chart cursors. */
  private render(t: number): void {
    const track = this.track;
    if (!track) return;
    this.t = t;
    if (!this.scrubbing) this.scrubber.value = String(t);
    this.element.dataset.replayT = t.toFixed(2);
    const state = track.stateAt(t);
    this.layer.moveTo(state.position, this.playing && this.follow.checked);
    this.scans.moveTo(track.origin + t);
    this.charts.setPosition(t);
    setText(this.values.time, `${formatClock(t)} / ${formatClock(track.duration)}`);
    setText(this.values.at, formatAuditTime(track.origin + t));
    this.eventFeed.showUntil(track.origin + t);
    setText(this.values.alt, formatAltitude(state.altRel));
    setText(this.values.groundspeed, formatSpeed(state.groundspeed));
    setText(this.values.battery, formatBatteryAt(state));
    setText(this.values.mode, state.mode ? `${state.mode}${state.armed === false ? " · disarmed" : ""}` : MISSING);
  }

  private setPlayButton(): void {
    this.playButton.textContent = this.playing ? "Pause" : "Play";
    this.playButton.setAttribute("aria-pressed", String(this.playing));
    this.element.dataset.playing = String(this.playing);
  }

  // ------------------------------------------------------------- view

  /** Stops playback and removes the flight from the map, the charts and the timeline. */
  private unload(): void {
    this.generation++;
    this.pause();
    this.track = null;
    this.t = 0;
    this.layer.clear();
    this.scans.clear();
    this.charts.destroy();
    this.eventTicks.replaceChildren();
    this.eventFeed.setEvents([]);
    this.scrubber.max = "0";
    this.scrubber.value = "0";
    delete this.element.dataset.flightId;
    delete this.element.dataset.replayT;
    this.list.select(null);
    this.setViewState("empty");
  }

  private showEventTicks(track: FlightTrack, events: FlightEvent[]): void {
    const duration = Math.max(track.duration, 1e-6);
    for (const event of events) {
      const t = track.clamp(event.time - track.origin);
      const tick = element("span", {
        className: `event-tick event-${eventTone(event)}`,
        title: event.text || event.kind,
      });
      tick.style.left = `${(t / duration) * 100}%`;
      tick.addEventListener("click", () => this.seek(t));
      this.eventTicks.append(tick);
    }
  }

  private setViewState(state: ReplayViewState, message = ""): void {
    this.view.dataset.state = state;
    this.view.hidden = state === "empty";
    this.status.textContent = message;
    this.status.hidden = message === "";
    const ready = state === "ready";
    this.playButton.disabled = !ready;
    this.scrubber.disabled = !ready;
    for (const link of this.exportLinks) link.hidden = state === "empty";
    if (!ready) {
      for (const node of [this.values.alt, this.values.groundspeed, this.values.battery, this.values.mode]) {
        setText(node, MISSING);
      }
      setText(this.values.time, "00:00:00 / 00:00:00");
      setText(this.values.at, "");
    }
  }
}
