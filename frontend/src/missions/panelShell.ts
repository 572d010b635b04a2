// The mission panel's frame: a map control in the top-right corner, its "Mission" button
// and the body that folds under it. Folding the body ends the panel's map tool (adding
// waypoints): a folded panel once went on taking the map's clicks, unseen.
import * as L from "leaflet";
import type { VehicleState } from "../hub/types";
import { mapToolsOf } from "../map/mapTools";
import { button, el } from "../ui/dom";

export interface PanelShell {
  element: HTMLElement;
  body: HTMLElement;
  control: L.Control;
}

export function missionPanelShell(map: L.Map): PanelShell {
  const element = el("div", "mission-panel");
  const toggle = button("mission-toggle", "Mission", "Show or edit the selected vehicle's mission");
  const body = el("div", "mission-body");
  body.hidden = true;
  toggle.addEventListener("click", () => {
    body.hidden = !body.hidden;
    toggle.setAttribute("aria-expanded", String(!body.hidden));
    if (body.hidden) mapToolsOf(map).endOwnedBy(element);
  });
  element.append(toggle, body);
  // Clicks and wheel turns on the panel stay off the map (no waypoint, no zoom).
  L.DomEvent.disableClickPropagation(element);
  L.DomEvent.disableScrollPropagation(element);
  const Panel = L.Control.extend({ onAdd: () => element });
  const control = new Panel({ position: "topright" });
  control.addTo(map);
  return { element, body, control };
}

/** Where the mission starts (and RTL returns to): home, else the vehicle's own position. */
export function missionHome(state: VehicleState | null | undefined): L.LatLng | null {
  if (state?.home_lat != null && state.home_lon != null) return L.latLng(state.home_lat, state.home_lon);
  if (state?.lat != null && state.lon != null && !(state.lat === 0 && state.lon === 0)) return L.latLng(state.lat, state.lon);
  return null;
}
