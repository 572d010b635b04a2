// The hub's store in the header: hidden while it takes every write, else what is held
// back and what was lost. The live view goes on without the store (commands too), so
// an operator may not notice a database outage or a full disk any other way; the flight
// log and the exports will miss what is lost.
import type { HubHealth } from "../hub/types";

const POLL_MS = 5_000;

export class StoreHealth {
  private timer: number | undefined;

  constructor(
    private readonly element: HTMLElement,
    private readonly fetchHealth: () => Promise<HubHealth>,
  ) {}

  start(): void {
    const poll = async () => {
      try {
        this.show(await this.fetchHealth());
      } catch {
        // The live feed's own status says when the hub is unreachable.
      }
      if (this.timer !== undefined) this.timer = window.setTimeout(poll, POLL_MS);
    };
    this.timer = window.setTimeout(poll, 0);
  }

  stop(): void {
    window.clearTimeout(this.timer);
    this.timer = undefined;
    this.element.hidden = true;
  }

  show(health: HubHealth): void {
    const lost = health.rows_lost ?? 0;
    const parts: string[] = [];
    if (!health.database_available) {
      parts.push(
        `Store unavailable: ${health.telemetry_backlog} samples and ${health.rows_spooled ?? 0} log rows held`,
      );
    }
    if (lost > 0) parts.push(`${lost} log rows lost`);
    this.element.dataset.state = health.database_available ? (lost > 0 ? "lossy" : "ok") : "degraded";
    this.element.textContent = parts.join(" · ");
    this.element.title = health.database_available
      ? "The store is back; some audit or command-log rows could not be kept"
      : "The hub cannot write to its database (down, or its disk full): live view and commands go on, and what is held is stored when it is back";
    this.element.hidden = parts.length === 0;
  }
}
