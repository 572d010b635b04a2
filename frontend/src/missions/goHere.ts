// "Fly here": right-click (or a long press on a touch screen) on the map offers to send
// the selected vehicle there at an altitude above home. The confirmation shows the
// distance and the rails' verdict on that go-to (`goto-check`, the same rails the `goto`
// command is held to) before anything is sent; a refused go-to cannot be confirmed. An
// accepted go-to closes the popup and its answer shows at the point for a few seconds.
//
// Not while a map tool is on (mapTools.ts): on a touch screen a long press is the same
// finger as a tap placing a corner or a waypoint, and a go-to opened (and confirmed) by
// mistake mid-drawing flies a real vehicle. The tool's banner says how to finish first.
import * as L from "leaflet";
import { runCommand } from "../hub/commands";
import type { VehicleSummary } from "../hub/types";
import { checkGoto } from "./api";
import { mapToolsOf } from "../map/mapTools";

const LONG_PRESS_MS = 600;
const DEFAULT_ALT_M = 10;
const CHECK_DELAY_MS = 250;
const ANSWER_SHOWN_MS = 4000;

function formatDistance(metres: number): string {
  return metres >= 1000 ? `${(metres / 1000).toFixed(2)} km` : `${Math.round(metres)} m`;
}

export class GoHere {
  private popup: L.Popup | null = null;
  private pressTimer: number | undefined;
  private pressStart: { x: number; y: number } | null = null;
  /** A long press opened the popup; the finger is still down. */
  private pressOpened = false;

  constructor(
    private readonly map: L.Map,
    private readonly selected: () => VehicleSummary | undefined,
  ) {
    map.on("contextmenu", this.onContextMenu);
    const container = map.getContainer();
    container.addEventListener("pointerdown", this.onPointerDown);
    container.addEventListener("pointermove", this.onPointerMove);
    container.addEventListener("pointerup", this.cancelPress);
    container.addEventListener("pointercancel", this.cancelPress);
    // Not passive: preventDefault is what keeps the lift from becoming a tap.
    container.addEventListener("touchend", this.onTouchEnd, { passive: false });
  }

  destroy(): void {
    this.map.off("contextmenu", this.onContextMenu);
    const container = this.map.getContainer();
    container.removeEventListener("pointerdown", this.onPointerDown);
    container.removeEventListener("pointermove", this.onPointerMove);
    container.removeEventListener("pointerup", this.cancelPress);
    container.removeEventListener("pointercancel", this.cancelPress);
    container.removeEventListener("touchend", this.onTouchEnd);
    this.cancelPress();
    this.popup?.remove();
  }

  private readonly onContextMenu = (event: L.LeafletMouseEvent): void => {
    L.DomEvent.preventDefault(event.originalEvent);
    if (mapToolsOf(this.map).active) return this.cancelPress();
    if (this.pressStart) {
      // A browser that makes a long press a "contextmenu" (Chrome on Android): one popup.
      this.cancelPress();
      this.pressOpened = true;
    }
    this.open(event.latlng);
  };

  // Leaflet turns a long press into "contextmenu" only on Safari: do it for every touch screen.
  private readonly onPointerDown = (event: PointerEvent): void => {
    if (event.pointerType !== "touch" || mapToolsOf(this.map).active) return;
    this.cancelPress();
    this.pressOpened = false;
    this.pressStart = { x: event.clientX, y: event.clientY };
    this.pressTimer = window.setTimeout(() => {
      const start = this.pressStart;
      this.pressStart = null;
      this.pressOpened = start !== null;
      if (start) this.open(this.map.mouseEventToLatLng({ clientX: start.x, clientY: start.y } as MouseEvent));
    }, LONG_PRESS_MS);
  };

  private readonly onPointerMove = (event: PointerEvent): void => {
    const start = this.pressStart;
    if (start && Math.hypot(event.clientX - start.x, event.clientY - start.y) > 10) this.cancelPress();
  };

  // A browser that fires no "contextmenu" on a long press (Chromium without a context
  // menu, among others) turns the lift into a tap, and a tap on the map closes its popup:
  // the one the press just opened.
  private readonly onTouchEnd = (event: TouchEvent): void => {
    if (!this.pressOpened) return;
    this.pressOpened = false;
    event.preventDefault();
  };

  private readonly cancelPress = (): void => {
    window.clearTimeout(this.pressTimer);
    this.pressStart = null;
  };

  private open(at: L.LatLng): void {
    const vehicle = this.selected();
    const box = document.createElement("div");
    box.className = "go-here";
    if (!vehicle) {
      box.textContent = "Select a vehicle first, then right-click (or long-press) where it should fly.";
      this.show(at, box);
      return;
    }
    const id = vehicle.id;
    const title = document.createElement("div");
    title.className = "go-here-title";
    title.textContent = `Fly ${id} here`;
    const altitude = document.createElement("input");
    altitude.type = "number";
    altitude.min = "1";
    altitude.max = "500";
    altitude.step = "any";
    altitude.dataset.field = "go-here-altitude";
    const flying = (vehicle.state?.alt_rel ?? 0) > 2;
    altitude.value = String(flying ? Math.round(vehicle.state?.alt_rel ?? DEFAULT_ALT_M) : DEFAULT_ALT_M);
    const altLabel = document.createElement("label");
    altLabel.append("at ", altitude, " m above home");
    const verdict = document.createElement("div");
    verdict.className = "go-here-verdict";
    verdict.dataset.field = "go-here-verdict";
    verdict.dataset.state = "pending";
    verdict.textContent = "Checking the rails…";
    const confirm = document.createElement("button");
    confirm.type = "button";
    confirm.className = "mission-button";
    confirm.dataset.action = "go-here-confirm";
    confirm.disabled = true;
    const cancel = document.createElement("button");
    cancel.type = "button";
    cancel.className = "mission-button";
    cancel.dataset.action = "go-here-cancel";
    cancel.textContent = "Cancel";
    cancel.addEventListener("click", () => this.popup?.remove());
    const result = document.createElement("div");
    result.className = "go-here-result";
    result.dataset.field = "go-here-result";
    const actions = document.createElement("div");
    actions.className = "go-here-actions";
    actions.append(confirm, cancel);
    box.append(title, altLabel, verdict, actions, result);

    let serial = 0;
    let timer: number | undefined;
    const check = () => {
      const alt = Number.parseFloat(altitude.value);
      confirm.textContent = `Fly here at ${Number.isFinite(alt) ? alt : "?"} m`;
      confirm.disabled = true;
      verdict.dataset.state = "pending";
      verdict.textContent = "Checking the rails…";
      if (!Number.isFinite(alt)) {
        verdict.textContent = "Give an altitude in metres.";
        return;
      }
      const mine = ++serial;
      checkGoto(id, at.lat, at.lng, alt)
        .then((answer) => {
          if (mine !== serial) return;
          const distance =
            answer.distance_m === null ? "distance unknown" : `${formatDistance(answer.distance_m)} away`;
          verdict.dataset.state = answer.ok ? "ok" : "refused";
          verdict.textContent = answer.ok
            ? `${distance} · rails: OK`
            : `${distance} · refused: ${answer.violations.map((v) => `${v.rule}: ${v.message}`).join("; ")}`;
          confirm.disabled = !answer.ok;
        })
        .catch((error: Error) => {
          if (mine !== serial) return;
          verdict.dataset.state = "error";
          verdict.textContent = `Could not check: ${error.message}`;
        });
    };
    altitude.addEventListener("input", () => {
      window.clearTimeout(timer);
      timer = window.setTimeout(check, CHECK_DELAY_MS);
    });
    confirm.addEventListener("click", () => {
      const alt = Number.parseFloat(altitude.value);
      confirm.disabled = true;
      result.textContent = "Sending…";
      void runCommand(id, { name: "goto", lat: at.lat, lon: at.lng, altitude: alt }).then((feedback) => {
        result.textContent = feedback.text;
        result.dataset.tone = feedback.tone;
        // Accepted: done with the popup. A refusal stays, its reason beside the altitude.
        if (feedback.tone === "accepted") this.answer(at, result);
      });
    });
    check();
    this.show(at, box);
  }

  /** The popup closes; its answer stays at the point a few seconds, out of the way. */
  private answer(at: L.LatLng, result: HTMLElement): void {
    this.popup?.remove();
    const tip = L.tooltip({ permanent: true, direction: "top", className: "go-here-answer" })
      .setLatLng(at)
      .setContent(result)
      .addTo(this.map);
    window.setTimeout(() => tip.remove(), ANSWER_SHOWN_MS);
  }

  private show(at: L.LatLng, content: HTMLElement): void {
    this.popup?.remove();
    L.DomEvent.disableClickPropagation(content);
    this.popup = L.popup({ className: "go-here-popup", minWidth: 220 })
      .setLatLng(at)
      .setContent(content)
      .openOn(this.map);
  }
}
