// One logged-in session of the dashboard: config -> map, WebSocket -> store ->
// views (each view subscribes to the slices of the store it draws). Built at login and torn down at logout or when the session ends, so the
// next user starts clean (and gets the controls their role allows).
import { checkSession, fetchConfig, fetchHealth } from "../hub/api";
import { AuditPanel } from "../audit/auditPanel";
import { runCommand } from "../hub/commands";
import { FleetSocket } from "../hub/connection";
import { DashboardStore } from "../store/dashboardStore";
import { FleetBatch } from "../store/fleetBatch";
import { FleetFold } from "../fleet/fleetFold";
import { FleetTable } from "../fleet/fleetTable";
import { FormationPanel } from "../formation";
import { linkState } from "../ui/format";
import { PROTOCOL_VERSION } from "../generated/protocol";
import type { Header } from "../header/header";
import { FleetMap } from "../map/fleetMap";
import { MapDock } from "../map/mapDock";
import { OpsPanels } from "../panels/opsPanels";
import { PilotPanel } from "../pilot/pilotPanel";
import { MissionTools } from "../missions";
import { ReplayPanel } from "../replay/replayPanel";
import { type CurrentUser, type HubConfig, type HubToClient, can } from "../hub/types";
import { ScanLayer } from "../scans/scanLayer";
import { StoreHealth } from "../header/storeHealth";
import { SurveyPanel } from "../survey";
import { Viz3dPane } from "../viz3d/pane";

// Without the hub's config there is no protocol version to compare: assume ours.
const OFFLINE_CONFIG: HubConfig = {
  basemap_url: null,
  basemap_attribution: "",
  basemap_max_zoom: 19,
  imagery_url: null,
  imagery_attribution: "",
  imagery_max_zoom: 19,
  protocol: PROTOCOL_VERSION,
};
/** setTimeout's ceiling (about 24.8 days). */
const MAX_TIMER_MS = 2 ** 31 - 1;

export interface DashboardHooks {
  /** The hub refused the session on the WebSocket (close code 4401). */
  onUnauthorized(reason: string): void;
  logout(): void;
}

export class Dashboard {
  private socket: FleetSocket | null = null;
  private map: FleetMap | null = null;
  private table: FleetTable | null = null;
  private fold: FleetFold | null = null;
  /** Re-fits the map, keeping its centre, whenever its area changes size (a docked panel, a drawer, a split). */
  private mapResize: ResizeObserver | null = null;
  private dock: MapDock | null = null;
  private scans: ScanLayer | null = null;
  private audit: AuditPanel | null = null;
  private replay: ReplayPanel | null = null;
  private store: DashboardStore | null = null;
  private fleet: FleetBatch | null = null;
  private ops: OpsPanels | null = null;
  private viz3d: Viz3dPane | null = null;
  private missions: MissionTools | null = null;
  private survey: SurveyPanel | null = null;
  private formation: FormationPanel | null = null;
  private pilot: PilotPanel | null = null;
  private expiryTimer: number | undefined;
  private storeHealth: StoreHealth | null = null;
  private stopped = false;

  constructor(
    private readonly user: CurrentUser,
    private readonly header: Header,
    private readonly hooks: DashboardHooks,
  ) {}

  async start(): Promise<void> {
    const { header, user, hooks } = this;
    header.setUser(user, {
      logout: () => hooks.logout(),
      toggleAudit: () => this.toggleAudit(),
      toggleFlights: () => this.toggleFlights(),
    });
    header.setCounts(0, 0);
    header.setConnection("connecting");
    this.watchExpiry();
    this.storeHealth = new StoreHealth(document.getElementById("store-status")!, fetchHealth);
    this.storeHealth.start();

    const config = await fetchConfig().catch((error: Error) => {
      if (!this.stopped) {
        header.showNotice(`Could not load the hub's config (${error.message}); showing no basemap.`);
      }
      return OFFLINE_CONFIG;
    });
    // A 401 on the config call ends the session (and stops this dashboard) meanwhile.
    if (this.stopped) return;
    if (config.protocol !== undefined && config.protocol !== PROTOCOL_VERSION) {
      header.showNotice(
        `The hub speaks protocol ${config.protocol}; this dashboard was built for ${PROTOCOL_VERSION}. Reload or rebuild it.`,
        true,
      );
    }

    const store = new DashboardStore();
    this.store = store;
    const map = new FleetMap(document.getElementById("map")!, config, store);
    this.map = map;
    this.mapResize = new ResizeObserver(() => {
      map.leaflet.invalidateSize({ animate: false });
      map.refitIfHidden();
    });
    this.mapResize.observe(document.getElementById("map")!);
    this.dock = new MapDock(document.getElementById("map")!, document.querySelector<HTMLElement>(".map-dock")!);
    this.fold = new FleetFold(document.querySelector<HTMLElement>(".fleet-panel")!);
    this.table = new FleetTable(
      document.querySelector<HTMLTableSectionElement>("#fleet-table tbody")!,
      can(user, "command") ? runCommand : null,
      store,
    );
    const ops = new OpsPanels(document.querySelector<HTMLElement>(".layout")!, can(user, "command") ? runCommand : null, store);
    this.ops = ops;
    // The pilot view sits under the selected vehicle's panel; it sends on this socket.
    const pilot = new PilotPanel(
      user,
      (message) => this.socket?.send(message) ?? false,
      can(user, "command") ? runCommand : null,
      (text) => header.showNotice(text),
      store,
    );
    ops.element.firstElementChild?.after(pilot.element);
    this.pilot = pilot;
    // Leaflet watches only the window: the split narrows the map itself.
    this.viz3d = new Viz3dPane(document.getElementById("map")!, store, () => map.leaflet.invalidateSize());
    this.missions = new MissionTools(map.leaflet, can(user, "command"), store);
    this.survey = new SurveyPanel(map.leaflet, can(user, "command"), store);
    this.formation = new FormationPanel(map.leaflet, can(user, "command"), store);
    const scans = new ScanLayer(map.leaflet, (message) => this.socket?.send(message), store);
    this.scans = scans;
    store.subscribe(
      (state) => state.fleet,
      ({ all }) => {
        let online = 0;
        for (const vehicle of all.values()) if (linkState(vehicle) !== "offline") online++;
        header.setCounts(all.size, online);
        this.fold?.setCount(all.size);
      },
    );
    const fleet = new FleetBatch((frame) => {
      if (!this.stopped) store.setFleet(frame);
    });
    this.fleet = fleet;

    const onMessage = (message: HubToClient) => {
      switch (message.type) {
        case "fleet":
          fleet.replaceAll(message.vehicles);
          break;
        case "vehicles":
          for (const vehicle of message.vehicles) fleet.upsert(vehicle);
          break;
        case "events":
          store.onEventBatch(message);
          break;
        case "error":
          header.showNotice(`Hub: ${message.message}`);
          break;
        case "survey":
          store.putSurvey(message);
          break;
        case "pong":
          pilot.onPong(message.nonce);
          break;
        case "lease":
          store.putLease(message);
          break;
        case "lease_refused":
          store.putRefusal(message);
          break;
        case "manual_echo":
          pilot.onEcho(message);
          break;
      }
    };

    this.socket = new FleetSocket({
      onMessage,
      onBinary: (data) => scans.onFrame(data),
      onState: (state, retry) => {
        if (!this.stopped) header.setConnection(state, retry);
        if (state === "connected") scans.resubscribe();
      },
      onUnauthorized: (reason) => hooks.onUnauthorized(reason),
      onForbidden: (reason) => header.showNotice(`The hub refused the live feed: ${reason}`, true),
      // A refused upgrade looks like any network failure to the browser: ask the hub
      // whether the session still holds (a 401 there shows the login screen).
      onAttemptFailed: () => void checkSession().catch(() => {}),
    });
    this.socket.start();
  }

  /** Closes the socket and removes every view; safe to call twice. */
  stop(): void {
    if (this.stopped) return;
    this.stopped = true;
    window.clearTimeout(this.expiryTimer);
    this.socket?.stop();
    this.socket = null;
    this.viz3d?.remove();
    this.viz3d = null;
    this.audit?.element.remove();
    this.audit = null;
    this.replay?.destroy();
    this.replay = null;
    document.querySelector(".layout")?.classList.remove("flights-open");
    this.store?.close();
    this.store = null;
    this.fleet = null;
    this.pilot?.destroy();
    this.pilot = null;
    this.ops?.destroy();
    this.ops = null;
    this.dock?.destroy();
    this.dock = null;
    this.missions?.destroy();
    this.missions = null;
    this.survey?.destroy();
    this.survey = null;
    this.formation?.destroy();
    this.formation = null;
    this.table?.destroy();
    this.table = null;
    this.fold?.destroy();
    this.fold = null;
    this.mapResize?.disconnect();
    this.mapResize = null;
    this.scans?.destroy();
    this.scans = null;
    this.map?.destroy();
    this.map = null;
    this.storeHealth?.stop();
    this.storeHealth = null;
    this.header.setConnection("stopped");
    this.header.setCounts(0, 0);
    this.header.setUser(null);
    this.header.clearNotice();
  }

  private toggleAudit(): void {
    if (this.stopped || !can(this.user, "audit")) return;
    if (!this.audit) {
      this.audit = new AuditPanel(() => this.toggleAudit());
      document.querySelector(".layout")!.append(this.audit.element);
    }
    if (this.audit.isOpen) this.audit.close();
    else this.audit.open();
    this.header.setAuditOpen(this.audit.isOpen);
  }

  /** Enters or leaves the flight replay mode (the panel takes the fleet table's place). */
  private toggleFlights(): void {
    const map = this.map;
    if (this.stopped || !map || !can(this.user, "read")) return;
    const layout = document.querySelector(".layout")!;
    if (!this.replay) {
      this.replay = new ReplayPanel(map, () => this.toggleFlights(), this.store!);
      layout.append(this.replay.element);
    }
    if (this.replay.isOpen) this.replay.close();
    else this.replay.open(this.fleet?.ids() ?? []);
    layout.classList.toggle("flights-open", this.replay.isOpen);
    this.header.setFlightsOpen(this.replay.isOpen);
  }

  /**
   * When the session's lifetime runs out, check with the hub (a 401 shows the login
   * screen). `minDelayMs` keeps a browser clock ahead of the hub's from polling fast.
   */
  private watchExpiry(minDelayMs = 1000): void {
    const expiresAt = this.user.expires_at;
    if (typeof expiresAt !== "number") return; // unknown: the next 401 will tell
    const untilMs = expiresAt * 1000 - Date.now();
    this.expiryTimer = window.setTimeout(
      () => {
        if (this.stopped) return;
        checkSession()
          .then((user) => {
            if (this.stopped) return;
            if (typeof user.expires_at === "number") this.user.expires_at = user.expires_at;
            this.watchExpiry(60_000);
          })
          .catch(() => {});
      },
      Math.min(Math.max(untilMs + 1000, minDelayMs), MAX_TIMER_MS),
    );
  }
}
