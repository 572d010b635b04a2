// The dock beside the map: a planning panel (mission, survey, formation) whose body is
// open stands here, beside the map (below it on a phone), and the map shrinks to the rest
// (the dashboard re-fits it), so the panel never covers the vehicles it acts on. Folded,
// the panel goes back to its place among the map's buttons. It watches the bodies'
// `hidden` attribute, so the panels need not know about it: however a panel opens (its
// button, a "show this mission" from elsewhere), it is docked.

/** The open/closed part of each dockable panel; its parent is the panel that moves. */
const BODIES = ".map-panel-body, .mission-body";

export class MapDock {
  /** Where each docked panel stood on the map. */
  private readonly homes = new Map<HTMLElement, HTMLElement>();
  private readonly observer: MutationObserver;

  constructor(
    private readonly map: HTMLElement,
    private readonly dock: HTMLElement,
  ) {
    this.observer = new MutationObserver(() => this.place());
    for (const root of [map, dock]) {
      this.observer.observe(root, { subtree: true, childList: true, attributes: true, attributeFilter: ["hidden"] });
    }
    this.place();
  }

  /** Every panel to where its body's state says; called on each change. */
  private place(): void {
    for (const body of this.map.querySelectorAll<HTMLElement>(BODIES)) {
      const panel = body.parentElement;
      if (!body.hidden && panel && !this.homes.has(panel)) this.moveIn(panel);
    }
    for (const [panel, home] of this.homes) {
      const body = panel.querySelector<HTMLElement>(BODIES);
      if (!panel.isConnected) this.forget(panel, home); // removed with its map control
      else if (!body || body.hidden) this.moveOut(panel, home);
    }
    const shown = this.homes.size > 0;
    if (this.dock.hidden === shown) this.dock.hidden = !shown;
  }

  private moveIn(panel: HTMLElement): void {
    // An empty box of the folded panel's (its button's) size keeps its place, so the buttons below it do
    // not slide up under the pointer (a hovered base-map list would open).
    const home = document.createElement("div");
    home.className = "docked-panel-place leaflet-control";
    home.style.height = `${panel.firstElementChild?.getBoundingClientRect().height ?? 0}px`;
    panel.before(home);
    this.homes.set(panel, home);
    this.dock.append(panel);
  }

  private moveOut(panel: HTMLElement, home: HTMLElement): void {
    this.homes.delete(panel);
    if (home.isConnected) home.replaceWith(panel);
    else panel.remove(); // its map control is gone: so is the panel
  }

  private forget(panel: HTMLElement, home: HTMLElement): void {
    this.homes.delete(panel);
    home.remove();
  }

  /** Puts every panel back (the session ended) and stops watching. */
  destroy(): void {
    this.observer.disconnect();
    for (const [panel, home] of [...this.homes]) this.moveOut(panel, home);
    this.dock.hidden = true;
  }
}
