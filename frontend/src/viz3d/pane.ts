// The 3D view beside the map or instead of it: the hub's viser scene (/viz/, behind the
// same login) in an iframe, in the part of the map's area that MapSplit gives it. The
// iframe is made only when the view opens, so a dashboard that never looks in 3D loads
// no viser. The two views select the same vehicle: the viewer's page tells us its id and
// a secret (backend/viz3d/viewers.py), with which we turn its camera to our selection; a
// click on a vehicle in 3D comes back as a message naming it.
import { selectInViewer } from "../hub/api";
import type { DashboardStore } from "../store/dashboardStore";
import { MapSplit, type SplitMode } from "./mapSplit";
import "./viz3d.css";

export const VIZ_URL = "/viz/";

interface ViewerMessage {
  type: "gcs-viz-viewer";
  viewer: number;
  secret: string;
}

interface SelectMessage {
  type: "gcs-viz-select";
  vehicle: string;
}

function barButton(text: string, action: string, onClick: () => void): HTMLButtonElement {
  const made = document.createElement("button");
  made.type = "button";
  made.className = "map-button";
  made.dataset.action = action;
  made.textContent = text;
  made.addEventListener("click", onClick);
  return made;
}

export class Viz3dPane {
  readonly button: HTMLButtonElement;
  readonly split: MapSplit;
  private readonly pane: HTMLElement;
  private readonly fullButton: HTMLButtonElement;
  private readonly closeButton: HTMLButtonElement;
  private frame: HTMLIFrameElement | null = null;
  private readonly resize: ResizeObserver;
  private viewer: { id: number; secret: string } | null = null;
  private selected: string | null = null;
  private readonly onMessage = (event: MessageEvent) => this.message(event);

  constructor(
    private readonly map: HTMLElement,
    private readonly store: DashboardStore,
    mapResized: () => void = () => undefined,
  ) {
    store.subscribe((state) => state.selection.id, (id) => id && this.select(id));
    window.addEventListener("message", this.onMessage);
    this.button = barButton("3D view", "viz3d-toggle", () => this.toggle());
    this.button.classList.add("viz3d-toggle");
    this.button.setAttribute("aria-pressed", "false");
    map.parentElement!.append(this.button);
    this.pane = document.createElement("section");
    this.pane.className = "viz3d-pane";
    this.pane.setAttribute("aria-label", "3D view");
    const bar = document.createElement("div");
    bar.className = "viz3d-bar";
    const title = document.createElement("span");
    title.className = "viz3d-title";
    title.textContent = "3D view";
    this.fullButton = barButton("Instead of the map", "viz3d-full", () => this.split.setFull(!this.split.full));
    this.closeButton = barButton("Close 3D view", "viz3d-close", () => this.toggle());
    bar.append(title, this.fullButton, this.closeButton);
    this.pane.append(bar);
    this.split = new MapSplit(map, this.pane, { mapResized, modeChanged: (mode) => this.modeChanged(mode) });
    this.resize = new ResizeObserver(() => this.placeButton());
    this.resize.observe(map);
    this.placeButton();
  }

  get isOpen(): boolean {
    return this.frame !== null;
  }

  toggle(): void {
    if (this.frame) {
      this.frame.remove();
      this.frame = null;
      this.viewer = null;
      this.split.setOpen(false);
      this.button.focus();
    } else {
      const frame = document.createElement("iframe");
      frame.src = VIZ_URL;
      frame.title = "3D view of the fleet";
      this.pane.append(frame);
      this.frame = frame;
      this.split.setOpen(true);
    }
    this.button.setAttribute("aria-pressed", String(this.isOpen));
  }

  /** Beside the map the bar offers the whole area; instead of it, the way back. On a
   * narrow screen (always instead) only the way back. */
  private modeChanged(mode: SplitMode): void {
    const narrow = mode === "instead" && !this.split.full;
    this.fullButton.hidden = narrow;
    this.fullButton.textContent = this.split.full ? "Beside the map" : "Instead of the map";
    this.closeButton.textContent = mode === "instead" ? "Back to map" : "Close 3D view";
    this.placeButton();
  }

  /** The toggle at the map's bottom left (the scale and notices stand above it). */
  private placeButton(): void {
    const { offsetLeft, offsetTop, offsetHeight } = this.map;
    this.button.style.left = `${offsetLeft + 10}px`;
    this.button.style.top = `${offsetTop + offsetHeight - 44}px`;
  }

  /** The map's selection: this dashboard's viewer turns to it (once it has said who it is). */
  select(id: string): void {
    if (id === this.selected) return;
    this.selected = id;
    this.turnViewer();
  }

  private turnViewer(): void {
    const viewer = this.viewer;
    if (!viewer || !this.selected) return;
    // A vehicle without a position yet is not in 3D (409): the view stays where it is.
    selectInViewer(viewer.id, viewer.secret, this.selected).catch(() => undefined);
  }

  private message(event: MessageEvent): void {
    // Only our own viewer's page, on our own origin, is listened to.
    if (event.origin !== window.location.origin || !this.frame || event.source !== this.frame.contentWindow) return;
    const data = event.data as ViewerMessage | SelectMessage | null;
    if (data?.type === "gcs-viz-viewer" && typeof data.viewer === "number" && typeof data.secret === "string") {
      this.viewer = { id: data.viewer, secret: data.secret };
      this.turnViewer();
    } else if (data?.type === "gcs-viz-select" && typeof data.vehicle === "string") {
      this.selected = data.vehicle; // already shown there: no need to turn the camera back
      this.store.select(data.vehicle, true);
    }
  }

  remove(): void {
    window.removeEventListener("message", this.onMessage);
    this.resize.disconnect();
    this.split.remove();
    this.button.remove();
  }
}
