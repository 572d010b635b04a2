// The live WebSocket to the hub: reconnects with exponential backoff (full jitter) and pings
// so that a silently dead link (common on field radios) is noticed. The browser
// sends the session cookie with the handshake; a hub that refuses the session
// closes with 4401, and then the socket stops instead of retrying forever.
import { apiUrl } from "./api";
import type { ClientToHub, HubToClient, Ping } from "./types";

export type ConnectionState = "connecting" | "connected" | "reconnecting" | "stopped";

/** `protocol.messages.CloseCode.UNAUTHORIZED`: no session, or it expired or was revoked. */
export const CLOSE_UNAUTHORIZED = 4401;
/** `protocol.messages.CloseCode.FORBIDDEN`: logged in, but not allowed (e.g. the page's origin). */
export const CLOSE_FORBIDDEN = 4403;

export interface FleetSocketHandlers {
  onMessage(message: HubToClient): void;
  /** A binary frame: a LIDAR scan the dashboard subscribed to (protocol/scans.py). */
  onBinary?(data: ArrayBuffer): void;
  /** `retryInMs` is set while waiting before the next attempt. */
  onState(state: ConnectionState, retryInMs?: number): void;
  /** The hub closed with 4401; the socket has stopped. */
  onUnauthorized(reason: string): void;
  /** The hub closed with 4403; retrying would not help, so the socket has stopped. */
  onForbidden(reason: string): void;
  /**
   * A connection attempt failed before it opened (e.g. the hub refused the upgrade
   * with an HTTP status the browser does not expose); a chance to check the session.
   */
  onAttemptFailed?(): void;
}

const MIN_BACKOFF_MS = 500;
const MAX_BACKOFF_MS = 5000;
const PING_EVERY_MS = 10_000;
/** No frame at all (not even a pong) for this long means the link is dead. */
const SILENCE_LIMIT_MS = 25_000;

export function socketUrl(): string {
  const url = apiUrl("ws");
  url.protocol = url.protocol === "https:" ? "wss:" : "ws:";
  return url.toString();
}

export class FleetSocket {
  private socket: WebSocket | null = null;
  private backoffMs = MIN_BACKOFF_MS;
  private retryTimer: number | undefined;
  private pingTimer: number | undefined;
  private lastFrameAt = 0;
  private nonce = 0;
  private stopped = false;

  constructor(private readonly handlers: FleetSocketHandlers) {}

  start(): void {
    this.stopped = false;
    this.connect("connecting");
  }

  stop(): void {
    this.stopped = true;
    window.clearTimeout(this.retryTimer);
    this.teardown();
    this.handlers.onState("stopped");
  }

  private connect(state: ConnectionState): void {
    this.handlers.onState(state);
    const socket = new WebSocket(socketUrl());
    socket.binaryType = "arraybuffer";
    this.socket = socket;
    let opened = false;
    socket.onopen = () => {
      opened = true;
      this.lastFrameAt = Date.now();
      this.handlers.onState("connected");
      this.pingTimer = window.setInterval(() => this.keepAlive(), PING_EVERY_MS);
    };
    socket.onmessage = (event: MessageEvent) => {
      this.lastFrameAt = Date.now();
      this.backoffMs = MIN_BACKOFF_MS; // the hub is really talking to us
      if (event.data instanceof ArrayBuffer) {
        this.handlers.onBinary?.(event.data);
        return;
      }
      const message = parse(event.data);
      if (message) this.handlers.onMessage(message);
    };
    socket.onclose = (event: CloseEvent) => {
      if (this.socket !== socket) return;
      this.teardown();
      if (this.stopped) return;
      if (event.code === CLOSE_UNAUTHORIZED) {
        this.stop();
        this.handlers.onUnauthorized(event.reason || "the hub refused the session");
        return;
      }
      if (event.code === CLOSE_FORBIDDEN) {
        this.stop();
        this.handlers.onForbidden(event.reason || "the hub refused the live feed");
        return;
      }
      this.scheduleReconnect();
      if (!opened) this.handlers.onAttemptFailed?.();
    };
    // onerror is always followed by onclose, which does the work.
  }

  /** Sends a message if the link is open; false if it is not (the caller retries on reconnect). */
  send(message: ClientToHub): boolean {
    const socket = this.socket;
    if (!socket || socket.readyState !== WebSocket.OPEN) return false;
    socket.send(JSON.stringify(message));
    return true;
  }

  private keepAlive(): void {
    const socket = this.socket;
    if (!socket || socket.readyState !== WebSocket.OPEN) return;
    if (Date.now() - this.lastFrameAt > SILENCE_LIMIT_MS) {
      socket.close(); // onclose will reconnect
      return;
    }
    const ping: Ping = { type: "ping", nonce: String(++this.nonce) };
    socket.send(JSON.stringify(ping));
  }

  private scheduleReconnect(): void {
    // Full jitter, the policy of common/retry.py: a wait drawn uniformly from [0, cap],
    // the cap doubling from MIN_BACKOFF_MS to MAX_BACKOFF_MS. Every dashboard that lost
    // one hub (a restart) would otherwise knock again at the same instants, every round.
    const delay = Math.round(Math.random() * this.backoffMs);
    this.backoffMs = Math.min(this.backoffMs * 2, MAX_BACKOFF_MS);
    this.handlers.onState("reconnecting", delay);
    this.retryTimer = window.setTimeout(() => this.connect("reconnecting"), delay);
  }

  private teardown(): void {
    window.clearInterval(this.pingTimer);
    const socket = this.socket;
    this.socket = null;
    if (socket) {
      socket.onopen = socket.onmessage = socket.onclose = null;
      if (socket.readyState === WebSocket.OPEN || socket.readyState === WebSocket.CONNECTING) {
        socket.close();
      }
    }
  }
}

function parse(data: unknown): HubToClient | null {
  if (typeof data !== "string") return null;
  try {
    const message: unknown = JSON.parse(data);
    if (message && typeof message === "object" && "type" in message) return message as HubToClient;
  } catch {
    // fall through
  }
  console.warn("ignoring malformed frame from hub", data);
  return null;
}
