// The mosaics of surveys that no longer fly, on the map from the hub's list
// (GET /api/v1/mosaics): a page opened after a survey ended, or after the hub restarted,
// still shows them. A survey that flies is the survey panel's to show, live.
import type * as L from "leaflet";

import type { DashboardStore } from "../store/dashboardStore";
import { listMosaics } from "./api";
import { mosaicLayer } from "./mosaicTiles";
import { ENDED } from "./progressView";

export class FinishedMosaics {
  private readonly layers = new Map<string, L.TileLayer>();
  /** Surveys the live feed says fly: never drawn here. */
  private readonly live = new Set<string>();
  private readonly unsubscribe: () => void;
  private destroyed = false;

  constructor(
    private readonly map: L.Map,
    store: DashboardStore,
  ) {
    this.unsubscribe = store.subscribe(
      (state) => state.surveys,
      (surveys) => {
        for (const update of surveys.values()) {
          if (ENDED.has(update.state)) continue;
          this.live.add(update.survey_id);
          this.layers.get(update.survey_id)?.remove();
          this.layers.delete(update.survey_id);
        }
      },
    );
    void this.load();
  }

  private async load(): Promise<void> {
    let mosaics;
    try {
      mosaics = await listMosaics();
    } catch {
      return; // a reader without the list, a hub going away: the map goes on without them
    }
    for (const mosaic of mosaics) {
      if (this.destroyed || this.live.has(mosaic.survey_id) || this.layers.has(mosaic.survey_id)) continue;
      const layer = mosaicLayer(this.map, mosaic);
      if (!layer) continue;
      this.layers.set(mosaic.survey_id, layer.addTo(this.map));
      layer.getContainer()?.setAttribute("data-survey-id", mosaic.survey_id); // made by addTo
    }
  }

  destroy(): void {
    this.destroyed = true;
    this.unsubscribe();
    for (const layer of this.layers.values()) layer.remove();
    this.layers.clear();
  }
}
