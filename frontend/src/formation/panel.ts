// The formation panel: choose the leader (a vehicle, or none for a virtual leader that
// flies the route itself) and the followers, the shape, spacing, speed, minimum
// separation and controller, and draw the leader's route on the map. Start asks the hub,
// which checks it all and says why it refuses; while the formation flies the panel polls
// its status (joining or formed, each follower's error from its slot), draws the slots
// around the leader, and offers a new shape or spacing and Stop.
import * as L from "leaflet";
import { droneColour } from "../map/droneColours";
import { FoldingPanel, MapClicks } from "../map/foldingPanel";
import { errorText } from "../hub/api";
import { button, el, numberField, say } from "../ui/dom";
import type { VehicleSummary } from "../hub/types";
import type { DashboardStore } from "../store/dashboardStore";
import {
  CONTROLLER_NAMES,
  type FormationBody,
  type FormationStatus,
  SHAPE_NAMES,
  type Shape,
  type StoredFormation,
  changeFormation,
  getFormation,
  listFormations,
  startFormation,
  stopFormation,
} from "./api";
import { type SlotDrawing, FormationLayer } from "./layer";
import { type LeaderPose, routePose, slotPlaces } from "./slots";
import { formationHeadline, routeEndText } from "./statusText";

const POLL_MS = 1000;

/** What a formation was started with: enough to place its slots while it flies. */
type Flown = Pick<FormationBody, "route" | "speed_ms" | "pause_s" | "shape" | "spacing_m">;

function select(field: string, options: readonly [string, string][]): HTMLSelectElement {
  const made = el("select", "map-panel-select", field);
  for (const [value, text] of options) made.append(new Option(text, value));
  return made;
}

function labelled(label: string, input: HTMLElement): HTMLLabelElement {
  const wrap = el("label", "map-panel-field");
  wrap.append(label, input);
  return wrap;
}

export class FormationPanel {
  readonly element: HTMLElement;
  private readonly panel: FoldingPanel;
  private readonly clicks: MapClicks;
  private readonly layer: FormationLayer;
  private readonly vehicles = new Map<string, VehicleSummary>();
  private readonly followers = new Map<string, { box: HTMLInputElement; up: HTMLInputElement }>();
  private route: L.LatLng[] = [];
  /** The formation followed: started here, or found flying when the dashboard opened. */
  private formationId: string | null = null;
  private flown: Flown | null = null;
  private status: FormationStatus | null = null;
  private pollTimer: number | undefined;
  private destroyed = false;

  private readonly statusLine: HTMLElement;
  private readonly planning: HTMLElement;
  private readonly progress: HTMLElement;
  private readonly leader: HTMLSelectElement;
  private readonly followerList: HTMLElement;
  private readonly shape: HTMLSelectElement;
  private readonly spacing: HTMLInputElement;
  private readonly speed: HTMLInputElement;
  private readonly separation: HTMLInputElement;
  private readonly altitude: HTMLInputElement;
  private readonly controller: HTMLSelectElement;
  private readonly drawButton: HTMLButtonElement;
  private readonly startButton: HTMLButtonElement;
  // in flight
  private readonly live: HTMLElement;
  private readonly liveShape: HTMLSelectElement;
  private readonly liveSpacing: HTMLInputElement;

  constructor(
    map: L.Map,
    private readonly canCommand: boolean,
    store: DashboardStore,
  ) {
    store.followFleet(this);
    this.layer = new FormationLayer(map);
    this.panel = new FoldingPanel(map, "formation", "Formation", "Fly vehicles in formation behind a leader");
    this.element = this.panel.element;
    const clickTool = { label: "Drawing formation route", owner: this.element, onEnd: () => this.renderRoute() };
    this.clicks = new MapClicks(map, (at) => (this.route.push(at), this.renderRoute()), clickTool);
    const shapes = Object.entries(SHAPE_NAMES);

    // -- the members
    this.leader = select("formation-leader", [["", "Virtual leader (none)"]]);
    this.leader.title = "The vehicle that flies the route; a virtual leader is the route itself";
    this.followerList = el("div", "formation-followers", "formation-followers");

    // -- the shape and the flight
    this.shape = select("formation-shape", shapes);
    this.controller = select("formation-controller", Object.entries(CONTROLLER_NAMES));
    const fields = el("div", "map-panel-fields");
    let wrap: HTMLLabelElement;
    fields.append(labelled("Shape", this.shape));
    [wrap, this.spacing] = numberField("formation-spacing", "Spacing m", "3", "Between neighbouring slots");
    fields.append(wrap);
    [wrap, this.speed] = numberField("formation-speed", "Speed m/s", "1.5", "The leader's speed along the route");
    fields.append(wrap);
    [wrap, this.separation] = numberField("formation-separation", "Min separation m", "2", "No two vehicles ever closer");
    fields.append(wrap);
    [wrap, this.altitude] = numberField("formation-altitude", "Route altitude m", "8", "The leader's altitude above home");
    fields.append(wrap, labelled("Controller", this.controller));

    // -- the route
    this.drawButton = button("formation-draw", "Draw route", "Click the map for each point of the leader's route");
    this.drawButton.addEventListener("click", () => this.startRoute());
    const finish = button("formation-finish", "Finish", "Stop adding points");
    finish.addEventListener("click", () => this.finishRoute());
    const clear = button("formation-clear", "Clear", "Remove the route");
    clear.addEventListener("click", () => {
      this.route = [];
      this.finishRoute();
    });
    const routeTools = el("div", "mission-toolbar");
    routeTools.append(this.drawButton, finish, clear);
    const hint = el("p", "mission-hint");
    hint.textContent = "Route: Draw route, click the map for each point (two at least), then Finish.";

    this.startButton = button("formation-start", "Start formation", "The hub checks it, then every member gets its slot");
    this.startButton.addEventListener("click", () => void this.start());
    this.planning = el("div", "formation-planning");
    this.planning.append(
      labelled("Leader", this.leader),
      this.followerList,
      fields,
      routeTools,
      hint,
      this.startButton,
    );
    this.planning.hidden = !canCommand;

    // -- the formation flying
    this.progress = el("div", "formation-progress", "formation-progress");
    this.progress.hidden = true;
    this.liveShape = select("formation-live-shape", shapes);
    [wrap, this.liveSpacing] = numberField("formation-live-spacing", "Spacing m", "3", "The new spacing");
    const apply = button("formation-change", "Change", "New slots in flight: the followers glide to them");
    apply.addEventListener("click", () => void this.change());
    const stop = button("formation-stop", "Stop formation", "Every member leaves the formation and holds");
    stop.addEventListener("click", () => void this.stop());
    this.live = el("div", "formation-live");
    const liveFields = el("div", "map-panel-fields");
    liveFields.append(labelled("Shape", this.liveShape), wrap);
    this.live.append(liveFields, apply, stop);
    this.live.hidden = true;

    this.statusLine = el("div", "mission-status", "formation-status");
    this.statusLine.setAttribute("role", "status");
    this.panel.body.append(this.progress, this.live, this.statusLine, this.planning);
    this.renderRoute();
    void this.followFlying();
  }

  update(vehicles: Iterable<VehicleSummary>): void {
    let added = false;
    for (const vehicle of vehicles) {
      if (!this.vehicles.has(vehicle.id)) added = true;
      this.vehicles.set(vehicle.id, vehicle);
    }
    if (added) this.renderMembers();
    this.renderSlots();
  }

  remove(id: string): void {
    this.vehicles.delete(id);
    this.renderMembers();
  }

  destroy(): void {
    this.destroyed = true;
    window.clearTimeout(this.pollTimer);
    this.clicks.destroy();
    this.panel.remove();
    this.layer.destroy();
  }

  // ------------------------------------------------------------------ planning

  private renderMembers(): void {
    const ids = [...this.vehicles.keys()].sort();
    const leader = this.leader.value;
    this.leader.replaceChildren(new Option("Virtual leader (none)", ""), ...ids.map((id) => new Option(id, id)));
    this.leader.value = ids.includes(leader) ? leader : "";
    const title = el("span", "formation-followers-title");
    title.textContent = "Followers (m above the leader):";
    const rows = ids.map((id) => {
      const known = this.followers.get(id);
      const box = known?.box ?? el("input", "formation-follower-box");
      box.type = "checkbox";
      const up = known?.up ?? el("input", "mission-number formation-follower-up");
      up.type = "number";
      up.step = "any";
      up.value ||= "0";
      up.title = `${id}'s height above the leader in its slot`;
      this.followers.set(id, { box, up });
      const row = el("label", "formation-follower");
      row.dataset.vehicleId = id;
      row.append(box, ` ${id} `, up);
      return row;
    });
    for (const id of [...this.followers.keys()]) if (!this.vehicles.has(id)) this.followers.delete(id);
    this.followerList.replaceChildren(title, ...rows);
  }

  private startRoute(): void {
    this.route = [];
    this.clicks.start();
    this.renderRoute();
  }

  private finishRoute(): void {
    this.clicks.stop();
    this.renderRoute();
  }

  private renderRoute(): void {
    this.layer.drawRoute(this.route, this.clicks.active);
    this.drawButton.classList.toggle("active", this.clicks.active);
    this.element.dataset.routePoints = String(this.route.length);
  }

  private request(): FormationBody | string {
    const number = (input: HTMLInputElement) => Number.parseFloat(input.value);
    const followers = [...this.followers.entries()]
      .filter(([, f]) => f.box.checked)
      .map(([vehicle_id, f]) => ({ vehicle_id, up: number(f.up) || 0 }));
    if (followers.length === 0) return "Choose at least one follower.";
    if (this.route.length < 2) return "Draw the leader's route: two points at least.";
    const alt_m = number(this.altitude);
    return {
      leader_id: this.leader.value || null,
      route: this.route.map((p) => ({ lat: p.lat, lon: p.lng, alt_m })),
      speed_ms: number(this.speed),
      pause_s: 0,
      followers,
      shape: this.shape.value as Shape,
      spacing_m: number(this.spacing),
      min_separation_m: number(this.separation),
      controller: this.controller.value as FormationBody["controller"],
    };
  }

  private async start(): Promise<void> {
    const body = this.request();
    if (typeof body === "string") {
      say(this.statusLine, body, true);
      return;
    }
    this.finishRoute();
    this.startButton.disabled = true;
    say(this.statusLine, "Checking and starting the formation…");
    try {
      const status = await startFormation(body);
      this.follow(status.id, body, `Formation ${status.id} started.`);
      this.show(status);
    } catch (error) {
      say(this.statusLine, errorText(error), true);
    } finally {
      this.startButton.disabled = false;
    }
  }

  // ------------------------------------------------------------------ flying

  /** A dashboard opened while a formation flies follows it. */
  private async followFlying(): Promise<void> {
    let flying: StoredFormation | undefined;
    try {
      flying = (await listFormations()).find((f) => f.stopped === null);
    } catch {
      return; // nothing to follow; the panel still plans
    }
    if (!flying || this.destroyed || this.formationId !== null) return;
    const request = flying.request as unknown as FormationBody;
    this.route = request.route.map((p) => L.latLng(p.lat, p.lon));
    this.renderRoute();
    this.follow(flying.id, request, `Formation ${flying.id} is flying.`);
    void this.poll();
  }

  private follow(id: string, flown: Flown, message: string): void {
    this.formationId = id;
    this.flown = flown;
    say(this.statusLine, message);
    window.clearTimeout(this.pollTimer);
    this.pollTimer = window.setTimeout(() => void this.poll(), POLL_MS);
  }

  private async poll(): Promise<void> {
    const id = this.formationId;
    if (!id || this.destroyed) return;
    try {
      const status = await getFormation(id);
      if (this.destroyed || id !== this.formationId) return;
      this.show(status);
      if (status.stopped !== null) return;
    } catch (error) {
      say(this.statusLine, `Formation ${id}: ${errorText(error)}`, true);
    }
    this.pollTimer = window.setTimeout(() => void this.poll(), POLL_MS);
  }

  private show(status: FormationStatus): void {
    const first = this.status?.id !== status.id;
    this.status = status;
    this.progress.hidden = false;
    this.progress.dataset.state = status.state;
    this.progress.dataset.formationId = status.id;
    const head = el("div", "formation-progress-head", "formation-state");
    head.textContent = formationHeadline(status);
    const routeEnd = el("div", "formation-route-end", "formation-route-end");
    routeEnd.textContent = routeEndText(status);
    const list = el("ul", "formation-tracking");
    Object.keys(status.slots).forEach((vehicleId, index) => {
      const live = status.tracking[vehicleId]?.live_xy_m;
      const item = el("li", "");
      item.dataset.vehicleId = vehicleId;
      if (live != null) item.dataset.errorM = live.toFixed(2);
      const swatch = el("span", "map-panel-swatch");
      swatch.style.background = droneColour(index);
      item.append(swatch, `${vehicleId}: ${live == null ? "no report yet" : `${live.toFixed(1)} m from its slot`}`);
      list.append(item);
    });
    this.progress.replaceChildren(head, routeEnd, list);
    const flying = status.stopped === null;
    this.live.hidden = !this.canCommand || !flying;
    this.planning.hidden = !this.canCommand || flying;
    if (first && flying) {
      if (this.flown?.shape) this.liveShape.value = this.flown.shape;
      if (this.flown?.spacing_m) this.liveSpacing.value = String(this.flown.spacing_m);
    }
    if (!flying) {
      this.layer.clearSlots();
      return;
    }
    this.renderSlots();
  }

  private leaderPose(status: FormationStatus): LeaderPose | null {
    if (status.leader_id !== null) {
      const state = this.vehicles.get(status.leader_id)?.state;
      if (state?.lat == null || state.lon == null) return null;
      return { lat: state.lat, lon: state.lon, headingRad: ((state.heading_deg ?? 0) * Math.PI) / 180 };
    }
    if (!this.flown) return null;
    const t = status.formed_at === null ? 0 : Date.now() / 1000 - status.formed_at;
    return routePose(this.flown.route, this.flown.speed_ms, this.flown.pause_s ?? 0, t);
  }

  private renderSlots(): void {
    const status = this.status;
    if (!status || status.stopped !== null) return;
    const pose = this.leaderPose(status);
    if (!pose) return;
    const drawings: SlotDrawing[] = [];
    [...slotPlaces(pose, status.slots)].forEach(([vehicleId, slot], index) => {
      const state = this.vehicles.get(vehicleId)?.state;
      const at: [number, number] | null = state?.lat != null && state.lon != null ? [state.lat, state.lon] : null;
      drawings.push({ vehicleId, colour: droneColour(index), slot, at });
    });
    this.layer.drawSlots(drawings);
  }

  private async change(): Promise<void> {
    const id = this.formationId;
    if (!id) return;
    const spacing = Number.parseFloat(this.liveSpacing.value);
    try {
      this.show(await changeFormation(id, { shape: this.liveShape.value as Shape, spacing_m: spacing }));
      say(this.statusLine, `New slots: ${SHAPE_NAMES[this.liveShape.value as Shape]}, ${spacing} m apart.`);
    } catch (error) {
      say(this.statusLine, errorText(error), true);
    }
  }

  private async stop(): Promise<void> {
    const id = this.formationId;
    if (!id) return;
    try {
      this.show(await stopFormation(id));
      window.clearTimeout(this.pollTimer);
      say(this.statusLine, `Formation ${id} stopped: every member holds where it is.`);
    } catch (error) {
      say(this.statusLine, errorText(error), true);
    }
  }
}
