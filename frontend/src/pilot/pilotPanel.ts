// The pilot view: take a vehicle's manual-control lease, fly it with on-screen sticks,
// the keyboard or a gamepad, and see what it does. Frames go out at 25 Hz only while
// this browser holds the lease and can vouch for its input: the page hidden, the window
// blurred, the gamepad gone or frozen, or the hub's link down stop them, and the panel
// says why; the agent's 0.5 s deadman then holds the vehicle and the lease ends. It
// never starts again by itself: the pilot takes control again. A refused request says
// why in words; where the vehicle's setup is why (ArduPilot's SYSID_MYGCS, PX4's
// COM_RC_IN_MODE), an admin may make the change the refusal names, after confirming it,
// through the hub's audited parameter write, and control is asked for again.
import type { Runner } from "../panels/selectedVehicle";
import { actionButton, element, field, setText } from "../ui/dom";
import type { LeaseRefusal, LeaseState, ManualEcho, ManualInput } from "../generated/protocol";
import type { ClientToHub, CurrentUser, VehicleSummary } from "../hub/types";
import type { DashboardStore } from "../store/dashboardStore";
import { changedValues } from "../store/store";
import { BUTTON_HOLD, BUTTON_SELECT, type InputSource, SOURCE_LABELS, type SourceName, TouchSticks, openSource } from "./inputs";
import { type PilotSettings, loadMapping, loadSettings } from "./settings";
import { HubPing } from "./hubPing";
import { PilotStats } from "./pilotStats";
import { confirmFix, writeFix } from "./refusalFix";
import { settingsFormParts } from "./settingsForm";
import { NOT_FLOWN, statusLine } from "./statusLine";
import { Shaper, toManualAxes } from "./shaping";
import "./pilot.css";

/** 25 Hz: what browser GCSs send, and the hub's floor for a lease's stream. */
export const SEND_INTERVAL_MS = 40;

export type Send = (message: ClientToHub) => boolean;

export class PilotPanel {
  readonly element: HTMLElement;
  /** Control asked for, no answer yet. */
  private asking = false;
  /** What the fix button is doing or why it failed; shown in the status line. */
  private fixNote: string | null = null;
  private vehicleId: string | null = null;
  private vehicle: VehicleSummary | null = null;
  private source: InputSource | null = null;
  private sourceName: SourceName = "touch";
  private settings: PilotSettings | null = null;
  private readonly mapping;
  private shaper: Shaper | null = null;
  private sending = false;
  private stoppedWhy: string | null = null;
  private seq = 0;
  private lastTickMs = 0;
  private timer: number | undefined;
  private readonly hubPing: HubPing;
  private windowFocused = true;
  private readonly listeners = new AbortController();
  private readonly stats = new PilotStats();
  private readonly ui: Record<"title" | "holder" | "status" | "axes", HTMLElement>;
  private readonly take: HTMLButtonElement;
  private readonly release: HTMLButtonElement;
  private readonly revoke: HTMLButtonElement;
  private readonly resume: HTMLButtonElement;
  private readonly fix: HTMLButtonElement;
  private readonly isAdmin: boolean;
  private readonly sourcePicker: HTMLSelectElement;
  private readonly sticks: HTMLElement;
  private readonly stickZones: [HTMLElement, HTMLElement];
  private readonly buttons: HTMLElement;
  private readonly settingsForm: HTMLElement;

  constructor(
    private readonly user: CurrentUser,
    private readonly send: Send,
    private readonly runCommand: Runner | null,
    private readonly notify: (text: string) => void,
    private readonly store: DashboardStore,
  ) {
    this.mapping = loadMapping(user.username);
    this.hubPing = new HubPing(send, (ms) => this.stats.showHubRoundTrip(ms));
    this.ui = {
      title: element("h2", { className: "panel-title", textContent: "Fly by hand" }),
      holder: field("p", "lease-holder", { className: "pilot-holder", textContent: "Select a vehicle" }),
      status: field("output", "pilot-status", { className: "pilot-status", textContent: NOT_FLOWN }),
      axes: field("code", "pilot-axes", { className: "pilot-axes" }),
    };
    this.ui.status.setAttribute("aria-live", "assertive");
    const canFly = runCommand !== null && user.permissions.includes("command");
    this.take = actionButton("take-control", "Take control", () => this.requestLease());
    this.release = actionButton("release-control", "Release", () => this.control("release"));
    this.revoke = actionButton("revoke-control", "Revoke", () => this.control("revoke"));
    this.resume = actionButton("resume-mission", "Resume mission", () => void this.resumeMission());
    this.isAdmin = user.permissions.includes("admin");
    this.fix = actionButton("apply-fix", "", () => void this.applyFix());
    this.fix.hidden = true;
    this.sourcePicker = field("select", "pilot-source", { className: "pilot-source" });
    for (const [name, label] of Object.entries(SOURCE_LABELS)) {
      this.sourcePicker.append(element("option", { value: name, textContent: label }));
    }
    this.sourcePicker.setAttribute("aria-label", "Input");
    this.sourcePicker.addEventListener("change", () => {
      this.sourceName = this.sourcePicker.value as SourceName;
      if (this.sending) this.startSource();
    });
    this.stickZones = [
      element("div", { className: "pilot-stick" }),
      element("div", { className: "pilot-stick" }),
    ];
    this.stickZones[0].dataset.stick = "left";
    this.stickZones[1].dataset.stick = "right";
    this.sticks = element("div", { className: "pilot-sticks", hidden: true }, ...this.stickZones);
    this.buttons = element(
      "div",
      { className: "pilot-buttons", hidden: true },
      actionButton("pilot-select", "Select (arm / land)", () => this.press(BUTTON_SELECT)),
      actionButton("pilot-hold", "Hold", () => this.press(BUTTON_HOLD)),
    );
    this.settingsForm = element("details", { className: "pilot-settings" });
    this.element = element(
      "section",
      { className: "pilot-panel" },
      this.ui.title,
      this.ui.holder,
      // One row: the input, then taking, giving back and (an admin) taking away control.
      element(
        "div",
        { className: "pilot-controls" },
        ...(canFly ? [this.sourcePicker, this.take, this.release] : []),
        ...(this.isAdmin ? [this.revoke] : []),
        ...(canFly ? [this.resume] : []),
      ),
      this.ui.status,
      canFly && this.isAdmin ? element("div", { className: "pilot-fix" }, this.fix) : element("span"),
      this.sticks,
      this.buttons,
      this.stats.element,
      this.ui.axes,
      canFly ? this.settingsForm : element("span"),
    );
    this.element.dataset.panel = "pilot";

    const options = { signal: this.listeners.signal };
    document.addEventListener("visibilitychange", () => this.check(), options);
    window.addEventListener("blur", () => ((this.windowFocused = false), this.check()), options);
    window.addEventListener("focus", () => (this.windowFocused = true), options);
    window.addEventListener("gamepaddisconnected", () => this.check(), options);
    store.subscribe((state) => state.selection.id, (id) => id && this.select(id));
    store.subscribe((state) => state.fleet, ({ changed }) => this.update(changed));
    // Every lease and refusal the hub sends is news, whichever vehicle it is about.
    store.subscribe(
      (state) => state.leases,
      (now, before) => {
        for (const lease of changedValues(now, before)) this.onLease(lease);
      },
    );
    store.subscribe(
      (state) => state.refusals,
      (now, before) => {
        for (const refusal of changedValues(now, before)) this.onRefusal(refusal);
      },
    );
    this.render();
  }

  private get leases(): ReadonlyMap<string, LeaseState> {
    return this.store.state.leases;
  }

  /** The last refusal of each vehicle, until control is asked for again or granted. */
  private get refusals(): ReadonlyMap<string, LeaseRefusal> {
    return this.store.state.refusals;
  }

  // -- what the store and the dashboard feed in -------------------------------------

  private select(vehicleId: string): void {
    if (vehicleId === this.vehicleId) return;
    if (this.sending) this.stop("another vehicle selected"); // its lease ends by the deadman
    this.vehicleId = vehicleId;
    this.vehicle = null;
    this.asking = false; // an answer about the other vehicle is no answer about this one
    this.fixNote = null;
    this.settings = loadSettings(this.user.username, vehicleId);
    this.renderSettings();
    this.render();
  }

  private update(changed: Iterable<VehicleSummary>): void {
    for (const vehicle of changed) if (vehicle.id === this.vehicleId) this.vehicle = vehicle;
    this.renderVehicle();
  }

  private onLease(state: LeaseState): void {
    if (state.vehicle_id !== this.vehicleId) return;
    const mine = state.holder === this.user.username;
    if (mine) {
      this.asking = false;
      this.store.clearRefusal(state.vehicle_id);
    }
    if (mine && !this.sending && this.stoppedWhy === null) this.startSending();
    if (!mine && this.sending) this.stop(`lease ended: ${state.reason || "no reason given"}`);
    if (!mine && state.holder === null && this.stoppedWhy !== null) {
      this.stoppedWhy = `${this.stoppedWhy}; lease ended: ${state.reason}`;
    }
    this.render();
  }

  /** The hub refused a `control` request of ours, with the reason (and maybe a fix). */
  private onRefusal(refusal: LeaseRefusal): void {
    if (refusal.vehicle_id !== this.vehicleId) return;
    this.asking = false;
    this.fixNote = null;
    this.render();
  }

  onPong(nonce: string | null | undefined): void {
    this.hubPing.onPong(nonce);
  }

  /** The agent flew our frame: its send time against now is input to vehicle and back. */
  onEcho(echo: ManualEcho): void {
    if (echo.vehicle_id !== this.vehicleId || typeof echo.sent_ms !== "number" || !this.sending) return;
    this.stats.showDelay(performance.now() - echo.sent_ms);
  }

  destroy(): void {
    this.stop("dashboard closed");
    this.listeners.abort();
    this.element.remove();
  }

  // -- the lease ------------------------------------------------------------------------

  private requestLease(): void {
    if (!this.vehicleId) return;
    this.stoppedWhy = null;
    this.fixNote = null;
    this.store.clearRefusal(this.vehicleId);
    this.asking = true;
    this.control("acquire");
    this.render();
  }

  /** An admin makes the change a refusal names (confirmed first; the hub audits the
   * write and checks the vehicle echoes it), then asks for control again. */
  private async applyFix(): Promise<void> {
    const vehicleId = this.vehicleId;
    const refusal = vehicleId ? this.refusals.get(vehicleId) : undefined;
    const fix = refusal?.fix;
    if (!vehicleId || !refusal || !fix || !confirmFix(vehicleId, refusal, fix)) return;
    this.fix.disabled = true;
    this.fixNote = `setting ${fix.param} to ${fix.value}…`;
    this.render();
    const failed = await writeFix(vehicleId, fix);
    this.fix.disabled = false;
    if (this.vehicleId !== vehicleId) return;
    if (failed === null) {
      this.requestLease();
    } else {
      this.fixNote = failed;
      this.render();
    }
  }

  private control(action: "acquire" | "release" | "revoke"): void {
    if (!this.vehicleId) return;
    if (action === "release") this.stop("released");
    if (!this.send({ type: "control", vehicle_id: this.vehicleId, action })) {
      this.notify("Not connected to the hub: try again when the link is back.");
    }
  }

  private async resumeMission(): Promise<void> {
    const mode = this.vehicleId ? this.leases.get(this.vehicleId)?.resume_mode : null;
    if (!this.vehicleId || !mode || !this.runCommand) return;
    const answer = await this.runCommand(this.vehicleId, { name: "set_mode", mode });
    setText(this.ui.status, answer.text);
  }

  // -- the stream -----------------------------------------------------------------------

  private startSource(): void {
    this.source?.destroy();
    const settings = this.settings ?? loadSettings(this.user.username, this.vehicleId ?? "");
    this.sticks.hidden = this.sourceName !== "touch";
    this.buttons.hidden = false;
    this.source = openSource(this.sourceName, this.stickZones, settings.keyboard, this.mapping);
    this.shaper = new Shaper(settings.shaping);
  }

  private startSending(): void {
    this.sending = true;
    this.stoppedWhy = null;
    this.startSource();
    this.lastTickMs = performance.now();
    this.timer = window.setInterval(() => this.tick(), SEND_INTERVAL_MS);
    this.hubPing.start();
    this.tick();
  }

  /** Why input must not go out now, or null. */
  private problem(nowMs: number): string | null {
    if (document.visibilityState === "hidden") return "page hidden";
    if (!this.windowFocused) return "window lost focus";
    return this.source?.problem(nowMs) ?? null;
  }

  private check(): void {
    if (!this.sending) return;
    const why = this.problem(performance.now());
    if (why) this.stop(why);
  }

  private tick(): void {
    if (!this.sending || !this.vehicleId || !this.source || !this.shaper) return;
    const now = performance.now();
    const reading = this.source.read(now);
    const why = this.problem(now);
    if (why) {
      this.stop(why); // never stream a value nobody vouches for
      return;
    }
    const shaped = this.shaper.shape(reading.axes, Math.min(0.2, (now - this.lastTickMs) / 1000));
    this.lastTickMs = now;
    const message: ManualInput = {
      type: "manual",
      vehicle_id: this.vehicleId,
      seq: ++this.seq,
      axes: toManualAxes(shaped, reading.buttons),
      source: this.source.name,
      sent_ms: now, // this page's monotonic clock; echoed back by the agent
    };
    if (!this.send(message)) {
      this.stop("link to the hub lost");
      return;
    }
    const axes = message.axes;
    setText(this.ui.axes, `x ${axes.x}  y ${axes.y}  z ${axes.z}  r ${axes.r}`);
  }

  private stop(why: string): void {
    if (this.sending) {
      this.stoppedWhy = why;
    }
    this.sending = false;
    window.clearInterval(this.timer);
    this.hubPing.stop();
    this.source?.destroy();
    this.source = null;
    this.sticks.hidden = true;
    this.buttons.hidden = true;
    this.render();
  }

  private press(bit: number): void {
    const source = this.source;
    if (source instanceof TouchSticks) source.presses.press(bit);
  }


  // -- drawing --------------------------------------------------------------------------

  private render(): void {
    const lease = this.vehicleId ? this.leases.get(this.vehicleId) : undefined;
    const holder = lease?.holder ?? null;
    const mine = holder === this.user.username;
    setText(this.ui.title, this.vehicleId ? `Fly ${this.vehicleId} by hand` : "Fly by hand");
    let holderText = "Select a vehicle";
    if (this.vehicleId) {
      holderText = holder ? `Flown by hand by ${holder}` : "Nobody flies it by hand";
      if (!holder && lease?.reason) holderText += ` (last lease: ${lease.reason})`;
    }
    setText(this.ui.holder, holderText);
    this.take.disabled = !this.vehicleId || holder !== null;
    this.release.disabled = !mine;
    this.revoke.disabled = !holder || mine;
    this.resume.hidden = !(lease?.resume_mode && !holder);
    if (lease?.resume_mode) this.resume.textContent = `Resume mission (${lease.resume_mode})`;
    const refusal = this.vehicleId ? this.refusals.get(this.vehicleId) : undefined;
    const status = statusLine({
      sendingWith: this.sending ? SOURCE_LABELS[this.sourceName] : null,
      asking: this.asking,
      fixNote: this.fixNote,
      refusal,
      isAdmin: this.isAdmin,
      stoppedWhy: this.stoppedWhy,
    });
    setText(this.ui.status, status.text);
    this.ui.status.dataset.state = status.state;
    const fix = !this.sending && !this.asking ? refusal?.fix : undefined;
    this.fix.hidden = !fix || !this.isAdmin;
    if (fix) setText(this.fix, `Set ${fix.param} to ${fix.value}`);
    this.renderVehicle();
  }

  private renderVehicle(): void {
    this.stats.show(this.vehicle);
  }

  private renderSettings(): void {
    const settings = this.settings;
    if (!settings || !this.vehicleId) return;
    this.settingsForm.replaceChildren(...settingsFormParts(this.user.username, this.vehicleId, settings, this.mapping));
  }
}
