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
