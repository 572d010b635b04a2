// What the dashboard's views draw, in one store: the fleet (one frame's changes at a
// time), the event log, the surveys, the manual-control leases and refusals, and the
// selected vehicle. The socket's messages and the views' clicks come in through the
// actions here; the views subscribe to the slices they draw (see store.ts).
import { EventLog, type IncomingEvent, type LogEvent } from "../events/eventLog";
import type { EventBatch, LeaseRefusal, LeaseState, LiveEvent, SurveyUpdate } from "../generated/protocol";
import type { VehicleSummary } from "../hub/types";
import type { FleetFrame } from "./fleetBatch";
import { Store } from "./store";

export interface Selection {
  id: string | null;
  /** Whether the map should bring it into view (a pick from the list, not the map). */
  pan: boolean;
}

export interface DashboardState {
  /** The last animation frame's changes, with the whole fleet as it is now. */
  fleet: FleetFrame;
  /** The event log, oldest first (a new array whenever events are added). */
  events: readonly LogEvent[];
  /** The latest update of each survey, by survey id. */
  surveys: ReadonlyMap<string, SurveyUpdate>;
  /** The manual-control lease of each vehicle, by vehicle id. */
  leases: ReadonlyMap<string, LeaseState>;
  /** The last refusal of our `control` requests, by vehicle id, until cleared. */
  refusals: ReadonlyMap<string, LeaseRefusal>;
  selection: Selection;
}

export function initialState(): DashboardState {
  return {
    fleet: { changed: [], removed: [], all: new Map() },
    events: [],
    surveys: new Map(),
    leases: new Map(),
    refusals: new Map(),
    selection: { id: null, pan: false },
  };
}

/** A view that draws each vehicle: told of the removed ones, then of the changed ones. */
export interface FleetView {
  update(changed: Iterable<VehicleSummary>): void;
  remove(id: string): void;
}

function withEntry<K, V>(map: ReadonlyMap<K, V>, key: K, value: V | undefined): ReadonlyMap<K, V> {
  const copy = new Map(map);
  if (value === undefined) copy.delete(key);
  else copy.set(key, value);
  return copy;
}

export class DashboardStore extends Store<DashboardState> {
  private readonly log: EventLog;

  constructor(eventLimit?: number) {
    super(initialState());
    this.log = new EventLog(eventLimit);
  }

  setFleet(frame: FleetFrame): void {
    this.set({ fleet: frame });
  }

  /** Hands `view` every frame of the fleet; returns the unsubscribe. */
  followFleet(view: FleetView): () => void {
    return this.subscribe(
      (state) => state.fleet,
      (frame) => {
        for (const id of frame.removed) view.remove(id);
        view.update(frame.changed);
      },
    );
  }

  /** Selects a vehicle (every click does, so `pan` asks the map again even for the same one). */
  select(id: string | null, pan: boolean): void {
    this.set({ selection: { id, pan } });
  }

  /** Adds events to the log: a batch from the hub, or ones a view worked out itself. */
  addEvents(events: Iterable<IncomingEvent | LiveEvent>): LogEvent[] {
    const added = this.log.add(events);
    if (added.length > 0) this.set({ events: [...this.log.all] });
    return added;
  }

  /** The live feed's `events` message; a note when the hub dropped some for us. */
  onEventBatch(batch: EventBatch, nowS = Date.now() / 1000): void {
    const events: IncomingEvent[] = [...batch.events];
    if (batch.dropped > 0) {
      events.push({
        vehicle_id: "hub",
        time: nowS,
        kind: "dropped",
        severity: 4,
        text: `${batch.dropped} less severe events were not sent: this dashboard fell behind`,
      });
    }
    this.addEvents(events);
  }

  putSurvey(update: SurveyUpdate): void {
    this.set({ surveys: withEntry(this.state.surveys, update.survey_id, update) });
  }

  putLease(lease: LeaseState): void {
    this.set({ leases: withEntry(this.state.leases, lease.vehicle_id, lease) });
  }

  putRefusal(refusal: LeaseRefusal): void {
    this.set({ refusals: withEntry(this.state.refusals, refusal.vehicle_id, refusal) });
  }

  clearRefusal(vehicleId: string): void {
    if (this.state.refusals.has(vehicleId)) this.set({ refusals: withEntry(this.state.refusals, vehicleId, undefined) });
  }
}
