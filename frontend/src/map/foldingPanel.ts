// A panel whose button sits in the map's top-right corner (the survey and formation
// panels): open, it stands in the map area's dock beside the map (map/mapDock.ts), so it
// never covers the vehicles it acts on. And the map clicks a panel draws with: while drawing, each click on the map is the
// panel's and the cursor is a crosshair.
import * as L from "leaflet";
import "./foldingPanel.css";
import { button, el } from "../ui/dom";

export class FoldingPanel {
  readonly element: HTMLElement;
  /** What folds open: the panel's content goes here. */
  readonly body: HTMLElement;
  private readonly control: L.Control;

  /** `name` makes the classes (`<name>-panel`, `<name>-body`) and the toggle's action (`<name>-toggle`). */
  constructor(map: L.Map, name: string, label: string, title: string) {
    this.element = el("div", `map-panel ${name}-panel`);
    const toggle = button(`${name}-toggle`, label, title);
    toggle.classList.add("map-panel-toggle");
    this.body = el("div", `map-panel-body ${name}-body`);
    this.body.hidden = true;
    toggle.setAttribute("aria-expanded", "false");
    toggle.addEventListener("click", () => {
      this.body.hidden = !this.body.hidden;
      toggle.setAttribute("aria-expanded", String(!this.body.hidden));
    });
    this.element.append(toggle, this.body);
    // Clicks and wheel turns on the panel stay off the map (no drawn vertex, no zoom).
    L.DomEvent.disableClickPropagation(this.element);
    L.DomEvent.disableScrollPropagation(this.element);
    const Panel = L.Control.extend({ onAdd: () => this.element });
    this.control = new Panel({ position: "topright" });
    this.control.addTo(map);
  }

  remove(): void {
    this.control.remove();
  }
}

/** Map clicks handed to `onClick` while drawing; off otherwise. */
export class MapClicks {
  private drawing = false;

  constructor(
    private readonly map: L.Map,
    private readonly onClick: (at: L.LatLng) => void,
  ) {
    map.on("click", this.handle);
  }

  get active(): boolean {
    return this.drawing;
  }

  start(): void {
    this.drawing = true;
    this.map.getContainer().classList.add("map-drawing-mode");
  }

  stop(): void {
    this.drawing = false;
    this.map.getContainer().classList.remove("map-drawing-mode");
  }

  destroy(): void {
    this.stop();
    this.map.off("click", this.handle);
  }

  private readonly handle = (event: L.LeafletMouseEvent): void => {
    if (this.drawing) this.onClick(event.latlng);
  };
}
