// The 3D view beside the map: the hub's viser scene (/viz/, behind the same login) in an
// iframe that takes the right half of the map's area while it is open. The iframe is
// made only when the pane opens, so a dashboard that never looks in 3D loads no viser.
export const VIZ_URL = "/viz/";

export class Viz3dPane {
  readonly button: HTMLButtonElement;
  private pane: HTMLElement | null = null;
  private readonly resize: ResizeObserver;

  constructor(private readonly map: HTMLElement) {
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

  remove(): void {
    this.resize.disconnect();
    this.pane?.remove();
    this.button.remove();
  }
}
