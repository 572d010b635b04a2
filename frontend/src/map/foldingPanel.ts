// A panel whose button sits in the map's top-right corner (the survey and formation
// panels): open, it stands in the map area's dock beside the map (map/mapDock.ts), so it
// never covers the vehicles it acts on. And the map clicks a panel draws with: while
// drawing, each click on the map is the panel's, the cursor is a crosshair and the map's
// banner names the tool.
import * as L from "leaflet";
import "./foldingPanel.css";
import { button, el } from "../ui/dom";
import { type MapTool, type MapToolRegistry, mapToolsOf } from "./mapTools";
import { showToolBanner } from "./toolBanner";

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
      // A folded panel draws nothing: its tool ends (it once drew on, unseen).
      if (this.body.hidden) mapToolsOf(map).endOwnedBy(this.element);
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

export interface MapClicksOptions {
  /** What the map's banner says while drawing, e.g. "Drawing survey area". */
  label: string;
  /** The panel the drawing belongs to (its element): folding it ends the drawing. */
  owner?: object;
  /** Something else ended the drawing (another tool, Esc, Done, a fold). */
  onEnd?: () => void;
}

/** Map clicks handed to `onClick` while drawing; off otherwise. Drawing is one of the
 * map's tools (mapTools.ts): starting it ends any other, and the banner shows it. */
export class MapClicks {
  private readonly tools: MapToolRegistry;
  private readonly tool: MapTool;

  constructor(
    private readonly map: L.Map,
    private readonly onClick: (at: L.LatLng) => void,
    options: MapClicksOptions,
  ) {
    this.tools = mapToolsOf(map);
    showToolBanner(map);
    this.tool = {
      label: options.label,
      owner: options.owner,
      ended: () => {
        this.crosshair(false);
        options.onEnd?.();
      },
    };
    map.on("click", this.handle);
  }

  get active(): boolean {
    return this.tools.isActive(this.tool);
  }

  start(): void {
    this.tools.start(this.tool);
    this.crosshair(true);
  }

  stop(): void {
    this.tools.release(this.tool);
    this.crosshair(false);
  }

  destroy(): void {
    this.stop();
    this.map.off("click", this.handle);
  }

  private crosshair(on: boolean): void {
    this.map.getContainer().classList.toggle("map-drawing-mode", on);
  }

  private readonly handle = (event: L.LeafletMouseEvent): void => {
    if (this.active) this.onClick(event.latlng);
  };
}
