// What the pilot sees of the vehicle while flying it by hand: its attitude, mode,
// altitude, speed, battery and position, and the two delays (input to vehicle and back,
// and the hub's round trip).
import { AttitudeIndicator } from "../panels/attitude";
import type { VehicleSummary } from "../hub/types";
import { element, field, setText } from "../ui/dom";
import { MISSING, formatAltitude, formatBattery, formatSpeed } from "../ui/format";

type StatName = "delay" | "rtt" | "alt" | "speed" | "battery" | "position" | "mode";

export class PilotStats {
  readonly element: HTMLElement;
  private readonly attitude = new AttitudeIndicator();
  private readonly values: Record<StatName, HTMLElement>;

  constructor() {
    const value = (name: string) => field("dd", name, { className: "stat-value", textContent: MISSING });
    this.values = {
      delay: value("pilot-delay"),
      rtt: value("pilot-hub-rtt"),
      alt: value("pilot-alt"),
      speed: value("pilot-speed"),
      battery: value("pilot-battery"),
      position: value("pilot-position"),
      mode: value("pilot-mode"),
    };
    const stat = (label: string, node: HTMLElement) =>
      element("div", { className: "stat" }, element("dt", { textContent: label }), node);
    this.element = element(
      "div",
      { className: "selected-body" },
      this.attitude.element,
      element(
        "dl",
        { className: "stats" },
        stat("Mode", this.values.mode),
        stat("Altitude", this.values.alt),
        stat("Speed", this.values.speed),
        stat("Battery", this.values.battery),
        stat("Position", this.values.position),
        stat("Input → vehicle (round trip)", this.values.delay),
        stat("Hub round trip", this.values.rtt),
      ),
    );
    this.attitude.element.dataset.field = "pilot-attitude";
  }

  /** The input-to-vehicle round trip (an echoed frame). */
  showDelay(ms: number): void {
    setText(this.values.delay, `${Math.round(ms)} ms`);
  }

  /** The hub's round trip (a pong). */
  showHubRoundTrip(ms: number): void {
    setText(this.values.rtt, `${Math.round(ms)} ms`);
  }

  show(vehicle: VehicleSummary | null): void {
    const state = vehicle?.state ?? null;
    setText(this.values.mode, state?.mode ?? MISSING);
    setText(this.values.alt, formatAltitude(state?.alt_rel));
    setText(this.values.speed, formatSpeed(state?.groundspeed));
    setText(this.values.battery, formatBattery(state));
    const lat = state?.lat;
    const lon = state?.lon;
    setText(this.values.position, typeof lat === "number" && typeof lon === "number" ? `${lat.toFixed(6)}, ${lon.toFixed(6)}` : MISSING);
    this.attitude.update(state?.roll_deg ?? 0, state?.pitch_deg ?? 0, state?.heading_deg ?? null);
  }
}
