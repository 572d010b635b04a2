// The map's area shared between the map and one view beside it (the 3D view), with a
// divider the operator drags or moves with the arrow keys.
//
// It works whatever the page's layout does with the map: it never moves #map. It makes
// one container (.viz3d-split) in the map's parent, placed over the map's right part,
// and narrows the map by the same width (width and margin, so the map's own cell, flex
// slot or absolute box keeps its size): the map's buttons and panels move left with
// the map instead of lying under the view. Where the area is too narrow for two views
// (a phone), or the operator asks for it, the view covers the whole area instead.
// The container's data-mode ("beside" | "instead") says which, for the page's CSS.
import {
  type SplitShare,
  MAX_SHARE,
  MIN_SHARE,
  NARROW_AREA_PX,
  clampShare,
  loadShare,
  saveShare,
  shareAfterKey,
} from "./splitShare";

export type SplitMode = "closed" | "beside" | "instead";

export class MapSplit {
  /** The container over the view's part of the map's area: the divider, then the view. */
  readonly element: HTMLDivElement;
  readonly divider: HTMLDivElement;
  private split: SplitShare = loadShare();
  private open = false;
  /** The width taken from the map's right side, in CSS pixels. */
  private reserved = 0;
  private mode: SplitMode = "closed";
  private readonly observer: ResizeObserver;
  private mapWidth = -1;
  /** Where on the divider the pointer took hold of it, so the divider does not jump to it. */
  private grip = 0;

  constructor(
    private readonly map: HTMLElement,
    view: HTMLElement,
    private readonly hooks: {
      /** The map's box changed size (Leaflet must be told: it watches only the window). */
      mapResized(): void;
      modeChanged(mode: SplitMode): void;
    },
  ) {
    this.element = document.createElement("div");
    this.element.className = "viz3d-split";
    this.element.hidden = true;
    this.divider = document.createElement("div");
    this.divider.className = "viz3d-divider";
    this.divider.tabIndex = 0;
    Object.entries({
      role: "separator",
      "aria-orientation": "vertical",
      "aria-label": "Resize the map and the 3D view (arrow keys)",
      "aria-valuemin": String(Math.round((1 - MAX_SHARE) * 100)),
      "aria-valuemax": String(Math.round((1 - MIN_SHARE) * 100)),
    }).forEach(([name, value]) => this.divider.setAttribute(name, value));
    this.element.append(this.divider, view);
    map.parentElement!.append(this.element);
    this.listen();
    this.observer = new ResizeObserver(() => this.place());
    this.observer.observe(map);
    this.observer.observe(map.parentElement!);
  }

  get current(): SplitMode {
    return this.mode;
  }

  /** The 3D view's share of the area while it is beside the map (0.2 to 0.8). */
  get share(): number {
    return this.split.share;
  }

  setOpen(open: boolean): void {
    this.open = open;
    this.place();
  }

  /** Instead of the map (true) or beside it (false), as the operator chose; remembered. */
  setFull(full: boolean): void {
    this.split = { ...this.split, full };
    saveShare(this.split);
    this.place();
  }

  get full(): boolean {
    return this.split.full;
  }

  private setShare(share: number): void {
    this.split = { ...this.split, share: clampShare(share) };
    this.place();
  }

  /** The map's area is its own box plus the width this split took from it. */
  private place(): void {
    const area = this.map.offsetWidth + this.reserved;
    const mode: SplitMode = !this.open
      ? "closed"
      : this.split.full || area < NARROW_AREA_PX
        ? "instead"
        : "beside";
    const reserve = mode === "beside" ? Math.round(area * this.split.share) : 0;
    if (reserve !== this.reserved) {
      this.map.style.width = reserve ? `calc(100% - ${reserve}px)` : "";
      this.map.style.marginRight = reserve ? `${reserve}px` : "";
      this.reserved = reserve;
    }
    this.element.hidden = mode === "closed";
    this.element.dataset.mode = mode;
    Object.assign(this.element.style, {
      left: `${this.map.offsetLeft + (mode === "beside" ? area - reserve : 0)}px`,
      top: `${this.map.offsetTop}px`,
      width: `${mode === "beside" ? reserve : area}px`,
      height: `${this.map.offsetHeight}px`,
    });
    const mapPercent = Math.round((1 - this.split.share) * 100);
    this.divider.setAttribute("aria-valuenow", String(mapPercent));
    this.divider.setAttribute("aria-valuetext", `map ${mapPercent} %, 3D view ${100 - mapPercent} %`);
    if (this.map.offsetWidth !== this.mapWidth) {
      this.mapWidth = this.map.offsetWidth;
      this.hooks.mapResized();
    }
    if (mode !== this.mode) {
      this.mode = mode;
      this.hooks.modeChanged(mode);
    }
  }

  private listen(): void {
    const divider = this.divider;
    divider.addEventListener("pointerdown", (event) => {
      if (event.button !== 0) return;
      event.preventDefault();
      divider.setPointerCapture(event.pointerId);
      this.grip = event.clientX - this.element.getBoundingClientRect().left;
      // The view's iframe would swallow the pointer's moves while it is over it.
      this.element.classList.add("dragging");
    });
    divider.addEventListener("pointermove", (event) => {
      if (!divider.hasPointerCapture(event.pointerId)) return;
      const area = this.map.offsetWidth + this.reserved;
      const right = this.element.getBoundingClientRect().right;
      this.setShare((right - event.clientX + this.grip) / area);
    });
    const end = (event: PointerEvent) => {
      if (!divider.hasPointerCapture(event.pointerId)) return;
      divider.releasePointerCapture(event.pointerId);
      this.element.classList.remove("dragging");
      saveShare(this.split);
    };
    divider.addEventListener("pointerup", end);
    divider.addEventListener("pointercancel", end);
    divider.addEventListener("keydown", (event) => {
      const share = shareAfterKey(this.split.share, event.key);
      if (share === null) return;
      event.preventDefault();
      this.setShare(share);
      saveShare(this.split);
    });
  }

  remove(): void {
    this.observer.disconnect();
    this.open = false;
    this.place();
    this.element.remove();
  }
}
