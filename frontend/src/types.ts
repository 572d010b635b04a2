// Friendlier names for the generated protocol types, plus the REST shapes that
// are not part of the WebSocket protocol bundle.
import type { CommandOutcome, CommandRequest } from "./generated/protocol";

export type {
  CommandOutcome,
  ErrorReply,
  FleetSnapshot,
  HubToClient,
  Ping,
  Pong,
  VehicleState,
  VehicleSummary,
  VehicleUpdate,
} from "./generated/protocol";

/** Body of `POST /api/v1/vehicles/{id}/commands`. */
export type Command = CommandRequest["command"];
export type CommandName = Command["name"];

/** 200 response of the command endpoint. */
export interface CommandResponse {
  vehicle_id: string;
  command: Command;
  outcome: CommandOutcome;
}

/** `GET /api/v1/config`. */
export interface HubConfig {
  basemap_url: string | null;
  basemap_attribution: string;
  basemap_max_zoom: number;
  /** The protocol version the hub speaks. */
  protocol?: number;
}

/** What the hub's permissions are called (`backend/auth/policy.py`). */
export type Permission = "read" | "command" | "audit" | "admin";
export type Role = "viewer" | "operator" | "admin";

/** `POST /api/v1/auth/login` and `GET /api/v1/auth/me`. */
export interface CurrentUser {
  username: string;
  role: Role | string;
  permissions: (Permission | string)[];
  /** Unix seconds; null or absent when the hub does not say (e.g. `/auth/me`). */
  expires_at?: number | null;
}

export function can(user: CurrentUser, permission: Permission): boolean {
  return user.permissions.includes(permission);
}

/** One row of `GET /api/v1/audit`. */
export interface AuditEntry {
  id: number;
  /** Unix seconds. */
  time: number;
  actor: string;
  role: string;
  source: string;
  action: string;
  target: string;
  outcome: "ok" | "refused" | "failed" | "denied" | string;
  detail: Record<string, unknown> | null;
}

export interface AuditPage {
  entries: AuditEntry[];
}

export interface AuditQuery {
  limit: number;
  /** Entries older than this id (paging). */
  beforeId?: number;
  actor?: string;
  action?: string;
}

// ---------------------------------------------------------------- flight logs

/** One row of `GET /api/v1/flights` (and `GET /api/v1/flights/{id}`). */
export interface Flight {
  id: number;
  vehicle_id: string;
  /** Unix seconds. */
  start_time: number;
  /** Unix seconds; null while the vehicle is still flying. */
  end_time: number | null;
  duration_s: number | null;
  distance_m: number | null;
  max_alt_m: number | null;
  battery_used_pct: number | null;
  samples: number | null;
}

export interface FlightPage {
  flights: Flight[];
  /** Pass as `before_id` for the next (older) page; null when there is none. */
  next_before_id: number | null;
}

export interface FlightQuery {
  limit: number;
  vehicleId?: string;
  beforeId?: number;
}

/** One sample of `GET /api/v1/flights/{id}/telemetry`. */
export interface FlightSample {
  /** Unix seconds. */
  time: number;
  lat: number | null;
  lon: number | null;
  alt_rel: number | null;
  alt_msl: number | null;
  heading_deg: number | null;
  groundspeed: number | null;
  climb_rate: number | null;
  battery_remaining: number | null;
  battery_voltage: number | null;
  mode: string | null;
  armed: boolean | null;
  gps_fix: number | null;
  satellites: number | null;
}

export interface FlightTelemetry {
  flight_id: number;
  vehicle_id: string;
  /** Sorted by time; downsampled by the hub with each bucket's extremes kept. */
  samples: FlightSample[];
}

export type FlightEventKind = "statustext" | "mode" | "armed" | "disarmed" | "link_up" | "link_down" | "failsafe";

/** One row of `GET /api/v1/events`. */
export interface FlightEvent {
  id: number;
  vehicle_id: string;
  /** Unix seconds. */
  time: number;
  kind: FlightEventKind | string;
  /** MAVLink severity: 0 emergency .. 7 debug; null when the kind has none. */
  severity: number | null;
  text: string;
}

export interface EventPage {
  events: FlightEvent[];
  next_before_id: number | null;
}

export interface EventQuery {
  vehicleId: string;
  /** Unix seconds. */
  start: number;
  end: number;
  limit: number;
  beforeId?: number;
}

export type FlightExportFormat = "csv" | "geojson" | "tlog";
