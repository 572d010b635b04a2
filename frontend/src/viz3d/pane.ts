// The 3D view beside the map: the hub's viser scene (/viz/, behind the same login) in an
// iframe that takes the right half of the map's area while it is open. The iframe is
// made only when the pane opens, so a dashboard that never looks in 3D loads no viser.
// The two views select the same vehicle: the viewer's page tells us its id and a secret
// (backend/viz3d/viewers.py), with which we turn its camera to our selection; a click on
// a vehicle in 3D comes back as a message naming it.
import { selectInViewer } from "../hub/api";
import type { DashboardStore } from "../store/dashboardStore";

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

export class Viz3dPane {
  readonly button: HTMLButtonElement;
  private pane: HTMLElement | null = null;
  private frame: HTMLIFrameElement | null = null;
  private readonly resize: ResizeObserver;
  private viewer: { id: number; secret: string } | null = null;
  private selected: string | null = null;
  private readonly onMessage = (event: MessageEvent) => this.message(event);

  constructor(
    private readonly map: HTMLElement,
    private readonly store: DashboardStore,
  ) {
    store.subscribe((state) => state.selection.id, (id) => id && this.select(id));
    window.addEventListener("message", this.onMessage);
    this.button = document.createElement("button");
    this.button.type = "button";
    this.button.className = "map-button viz3d-toggle";
    this.button.textContent = "3D view";
    this.button.setAttribute("aria-pressed", "false");
    this.button.addEventListener("click", () => this.toggle());
    map.parentElement!.append(this.button);
    this.resize = new ResizeObserver(() => this.place());
    this.resize.observe(map);
    this.place();
  }

  get isOpen(): boolean {
    return this.pane !== null;
  }

  toggle(): void {
    if (this.pane) {
      this.pane.remove();
      this.pane = null;
      this.frame = null;
      this.viewer = null;
    } else {
      const pane = document.createElement("section");
      pane.className = "viz3d-pane";
      pane.setAttribute("aria-label", "3D view");
      const frame = document.createElement("iframe");
      frame.src = VIZ_URL;
      frame.title = "3D view of the fleet";
      pane.append(frame);
      this.map.parentElement!.append(pane);
      this.pane = pane;
      this.frame = frame;
    }
    this.button.setAttribute("aria-pressed", String(this.isOpen));
    this.place();
  }

  /** The pane over the map's right half, and the button at the map's bottom left. */
  private place(): void {
    const { offsetLeft, offsetTop, offsetWidth, offsetHeight } = this.map;
    this.button.style.left = `${offsetLeft + 10}px`;
    this.button.style.top = `${offsetTop + offsetHeight - 44}px`;
    if (this.pane) {
      const half = Math.round(offsetWidth / 2);
      Object.assign(this.pane.style, {
        left: `${offsetLeft + offsetWidth - half}px`,
        top: `${offsetTop}px`,
        width: `${half}px`,
        height: `${offsetHeight}px`,
      });
    }
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
    this.pane?.remove();
    this.button.remove();
  }
}
