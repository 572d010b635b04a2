// Friendlier names for the generated types: the WebSocket protocol's
// (generated/protocol.ts, from protocol/messages/) and the REST API's (generated/api.ts,
// from the hub's OpenAPI document). Only the dashboard's own shapes are written here.
import type { components, paths } from "../generated/api";
import type { Event } from "../generated/protocol";

export type {
  ClientToHub,
  CommandOutcome,
  ErrorReply,
  FleetSnapshot,
  HubToClient,
  Ping,
  Pong,
  VehicleBatch,
  VehicleChange,
  VehicleState,
  VehicleSummary,
} from "../generated/protocol";

type Schemas = components["schemas"];

/** Body of `POST /api/v1/vehicles/{id}/commands`. */
export type Command = NonNullable<
  paths["/api/v1/vehicles/{vehicle_id}/commands"]["post"]["requestBody"]
>["content"]["application/json"];
export type CommandName = Command["name"];

/** 200 response of the command endpoint. */
export type CommandResponse = Schemas["CommandResponse"];

/** `GET /api/v1/config`. */
export type HubConfig = Schemas["ClientConfig"];
export type ParamValues = Schemas["ParamValues"];

/** `GET /api/v1/health`: the hub's store, as the dashboard's header reports it. */
export type HubHealth = Schemas["Health"];

/** What a user's permissions (its token's scopes) are called (`backend/auth/policy.py`,
 * `UserScope`; `agent` is an agent token's alone). */
export type Permission = NonNullable<
  Schemas["ApiTokenRequest"]["scopes"]
>[number];
export type Role = Schemas["Role"];

/** `POST /api/v1/auth/login` and `GET /api/v1/auth/me`. */
export type CurrentUser = Schemas["Identity"];

export function can(user: CurrentUser, permission: Permission): boolean {
  return user.permissions.includes(permission);
}

/** One row of `GET /api/v1/audit`. */
export type AuditEntry = Schemas["AuditRecord"];
export type AuditPage = Schemas["AuditPage"];
export type AuditAction = Schemas["AuditAction"];

export interface AuditQuery {
  limit: number;
  /** Entries older than this id (paging). */
  beforeId?: number;
  actor?: string;
  action?: string;
}

// ---------------------------------------------------------------- flight logs

/** One row of `GET /api/v1/flights` (and `GET /api/v1/flights/{id}`). */
export type Flight = Schemas["Flight"];
export type FlightPage = Schemas["FlightPage"];

export interface FlightQuery {
  limit: number;
  vehicleId?: string;
  beforeId?: number;
}

/** One sample of `GET /api/v1/flights/{id}/telemetry`. */
export type FlightSample = Schemas["Sample"];
export type FlightTelemetry = Schemas["FlightTelemetry"];

/** One row of `GET /api/v1/events`: `kind` is a string, since the hub also stores kinds of its own. */
export type FlightEvent = Schemas["EventRecord"];
/** The event kinds agents send; the hub adds its own (`data_lost`, ...). */
export type FlightEventKind = Event["kind"];
export type EventPage = Schemas["EventPage"];

export interface EventQuery {
  vehicleId: string;
  /** Unix seconds. */
  start: number;
  end: number;
  limit: number;
  beforeId?: number;
}

export type FlightExportFormat =
  paths["/api/v1/flights/{flight_id}/export.{format}"]["get"]["parameters"]["path"]["format"];

/** One broken safety rule in a 422 refusal (`violations` of the body). */
export type SafetyViolation = Schemas["ViolationModel"];
