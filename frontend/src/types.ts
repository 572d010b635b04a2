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
