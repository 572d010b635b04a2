// The operator's event log: what the vehicles and the hub reported (the live feed's
// `events` batches, or a stored flight's events in the replay), newest last, bounded,
// with each event's category worked out once. Vehicle text is data: it is only ever
// shown with textContent (see eventFeed.ts).
import type { LiveEvent } from "../generated/protocol";

/** MAV_SEVERITY: 0 emergency, 1 alert, 2 critical, 3 error, 4 warning, 5 notice, 6 info, 7 debug. */
export const SEVERITY_NAMES = ["emergency", "alert", "critical", "error", "warning", "notice", "info", "debug"];
/** Emergency, alert and critical: shown on the vehicle's row until acknowledged. */
export const CRITICAL_SEVERITY = 2;
export const MAX_EVENTS = 2000;

export type EventCategory = "prearm" | "failsafe" | "battery" | "command" | "mode" | "link" | "mission" | "text";

export interface LogEvent {
  /** Unique within the page, for acknowledgement and the DOM. */
  id: number;
  vehicleId: string;
  time: number;
  kind: string;
  severity: number | null;
  text: string;
  repeat: number;
  category: EventCategory;
}

// ArduPilot says "PreArm: ..." on its periodic checks and "Arm: ..." when an arming
// attempt is refused (AP_Arming::check_failed); PX4 says "Preflight Fail: ..." and
// "Arming denied! ...".
const PREARM = /^(PreArm|Arm):|^Preflight Fail|^Arming denied/i;
// ArduPilot's AP_BattMonitor: "Battery 1 is low 14.30V used 4000 mAh" / "... is critical";
// PX4: "Low battery level!", "Critical battery level!", "Emergency battery level!".
const BATTERY_FAILSAFE = /^Battery \d+ is (low|critical)|(low|critical|emergency|dangerous) battery level/i;
const FAILSAFE = /failsafe/i;

export function categorize(kind: string, text: string): EventCategory {
  if (kind === "failsafe") return BATTERY_FAILSAFE.test(text) ? "battery" : "failsafe";
  if (kind === "command") return "command";
  if (kind === "mode" || kind === "armed" || kind === "disarmed") return "mode";
  if (kind === "link_up" || kind === "link_down" || kind === "data_lost" || kind === "id_clash") return "link";
  if (kind === "mission") return "mission";
  if (PREARM.test(text)) return "prearm";
  if (BATTERY_FAILSAFE.test(text)) return "battery";
  if (FAILSAFE.test(text)) return "failsafe";
  return "text";
}

export function severityName(severity: number | null): string {
  return severity === null ? "—" : (SEVERITY_NAMES[severity] ?? String(severity));
}

/** Without a severity, an event ranks by what it is: a failsafe or link loss is critical. */
export function effectiveSeverity(event: Pick<LogEvent, "severity" | "kind" | "category">): number {
  if (event.severity !== null) return event.severity;
  if (event.kind === "link_down" || event.category === "failsafe" || event.category === "battery") return 2;
  return 6;
}

export interface IncomingEvent {
  vehicle_id: string;
  time: number;
  kind: string;
  severity?: number | null;
  text: string;
  repeat?: number;
}

export class EventLog {
  private events: LogEvent[] = [];
  private nextId = 1;
  /** Events already held, so a replayed or resent frame is not shown twice. */
  private readonly seen = new Set<string>();

  constructor(private readonly limit = MAX_EVENTS) {}

  get all(): readonly LogEvent[] {
    return this.events;
  }

  /** Adds events (any order); returns the ones that were new, oldest first. */
  add(incoming: Iterable<IncomingEvent | LiveEvent>): LogEvent[] {
    const added: LogEvent[] = [];
    for (const raw of incoming) {
      const key = `${raw.vehicle_id}\u0000${raw.time}\u0000${raw.kind}\u0000${raw.text}`;
      if (this.seen.has(key)) continue;
      this.seen.add(key);
      const severity = raw.severity ?? null;
      const event: LogEvent = {
        id: this.nextId++,
        vehicleId: raw.vehicle_id,
        time: raw.time,
        kind: raw.kind,
        severity,
        text: raw.text,
        repeat: raw.repeat ?? 1,
        category: categorize(raw.kind, raw.text),
      };
      added.push(event);
    }
    if (added.length === 0) return added;
    this.events.push(...added);
    // Mostly in order already: a backlog replayed after an outage is the exception.
    this.events.sort((a, b) => a.time - b.time || a.id - b.id);
    if (this.events.length > this.limit) {
      for (const old of this.events.splice(0, this.events.length - this.limit)) {
        this.seen.delete(`${old.vehicleId}\u0000${old.time}\u0000${old.kind}\u0000${old.text}`);
      }
    }
    return added.sort((a, b) => a.time - b.time || a.id - b.id);
  }

  clear(): void {
    this.events = [];
    this.seen.clear();
  }
}
