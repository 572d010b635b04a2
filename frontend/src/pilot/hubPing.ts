// The hub's round trip while flying by hand: a `ping` a second, timed by its `pong`.
// Only the newest ping counts, so a late pong never reports an old, slower trip.
import type { ClientToHub } from "../hub/types";

const PING_EVERY_MS = 1000;

export class HubPing {
  private timer: number | undefined;
  private nonce = 0;
  private readonly sentAt = new Map<string, number>();

  constructor(
    private readonly send: (message: ClientToHub) => boolean,
    private readonly onRoundTrip: (ms: number) => void,
  ) {}

  start(): void {
    window.clearInterval(this.timer);
    this.timer = window.setInterval(() => this.ping(), PING_EVERY_MS);
    this.ping();
  }

  stop(): void {
    window.clearInterval(this.timer);
  }

  onPong(nonce: string | null | undefined): void {
    if (!nonce) return;
    const sentAt = this.sentAt.get(nonce);
    if (sentAt === undefined) return;
    this.sentAt.delete(nonce);
    this.onRoundTrip(performance.now() - sentAt);
  }

  private ping(): void {
    const nonce = `pilot-${++this.nonce}`;
    this.sentAt.clear();
    this.sentAt.set(nonce, performance.now());
    this.send({ type: "ping", nonce });
  }
}
