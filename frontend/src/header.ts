// The header: connection status, vehicle count and a transient notice line.
import type { ConnectionState } from "./connection";

const NOTICE_MS = 10_000;

export class Header {
  private readonly status = document.getElementById("connection-status")!;
  private readonly count = document.getElementById("vehicle-count")!;
  private readonly notice = document.getElementById("notice")!;
  private noticeTimer: number | undefined;

  setConnection(state: ConnectionState, retryInMs?: number): void {
    this.status.dataset.state = state;
    document.body.dataset.connection = state;
    this.status.textContent =
      state === "connected"
        ? "Connected"
        : state === "connecting"
          ? "Connecting…"
          : retryInMs === undefined
            ? "Reconnecting…"
            : `Reconnecting in ${(retryInMs / 1000).toFixed(1)} s`;
  }

  setCounts(total: number, online: number): void {
    this.count.dataset.count = String(total);
    this.count.dataset.online = String(online);
    const noun = total === 1 ? "vehicle" : "vehicles";
    this.count.textContent = total === online ? `${total} ${noun}` : `${total} ${noun} · ${online} online`;
  }

  /** Shows `text` for a while, or until replaced when `sticky`. */
  showNotice(text: string, sticky = false): void {
    this.notice.textContent = text;
    this.notice.title = text;
    this.notice.hidden = false;
    window.clearTimeout(this.noticeTimer);
    if (!sticky) this.noticeTimer = window.setTimeout(() => (this.notice.hidden = true), NOTICE_MS);
  }
}
