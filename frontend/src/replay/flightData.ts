// What a flight's replay needs from the hub: its samples and its events (paged), and the
// links to its exports.
import { apiUrl, fetchEvents, fetchFlightTelemetry, flightExportUrl } from "../hub/api";
import type { Flight, FlightEvent, FlightExportFormat } from "../hub/types";
import { FlightTrack } from "./replayTrack";

/** Samples asked of the hub per flight (it keeps each bucket's extremes). */
const TELEMETRY_POINTS = 2000;
const EVENT_PAGE = 500;
const MAX_EVENT_PAGES = 4;

interface FlightExport {
  format: FlightExportFormat | "ply";
  label: string;
  title: string;
  url: (id: number) => string;
}

export const EXPORTS: FlightExport[] = [
  { format: "csv", label: "CSV", title: "Samples as CSV", url: (id) => flightExportUrl(id, "csv") },
  { format: "geojson", label: "GeoJSON", title: "Track as GeoJSON", url: (id) => flightExportUrl(id, "geojson") },
  { format: "tlog", label: "tlog", title: "MAVLink telemetry log", url: (id) => flightExportUrl(id, "tlog") },
  // The LIDAR's world points of the flight, for CloudCompare or PDAL (none without scans).
  {
    format: "ply",
    label: "Points",
    title: "LIDAR world points as PLY",
    url: (id) => apiUrl(`flights/${id}/points.ply`).toString(),
  },
];

async function flightEvents(flight: Flight): Promise<FlightEvent[]> {
  const events: FlightEvent[] = [];
  let beforeId: number | undefined;
  for (let page = 0; page < MAX_EVENT_PAGES; page++) {
    const answer = await fetchEvents({
      vehicleId: flight.vehicle_id,
      start: flight.start_time,
      end: flight.end_time ?? Date.now() / 1000,
      limit: EVENT_PAGE,
      beforeId,
    });
    events.push(...answer.events);
    if (answer.next_before_id === null || answer.next_before_id === undefined) break;
    beforeId = answer.next_before_id;
  }
  return events.sort((a, b) => a.time - b.time || a.id - b.id);
}

export interface LoadedFlight {
  track: FlightTrack;
  events: FlightEvent[];
  /** Why the events could not be loaded ("" when they were): the track replays without. */
  eventsFailed: string;
}

/** The flight's samples and events, asked for together; fails only when the samples do. */
export async function loadFlight(flight: Flight): Promise<LoadedFlight> {
  let events: FlightEvent[] = [];
  let eventsFailed = "";
  const eventsLoaded = flightEvents(flight).then(
    (loaded) => (events = loaded),
    (error: unknown) => (eventsFailed = error instanceof Error ? error.message : String(error)),
  );
  const telemetry = await fetchFlightTelemetry(flight.id, TELEMETRY_POINTS);
  await eventsLoaded;
  return { track: new FlightTrack(flight, telemetry.samples), events, eventsFailed };
}
