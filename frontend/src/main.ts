// Entry point: asks the hub who is logged in, then shows either the login screen
// or the dashboard. Any 401 (REST) or 4401 (WebSocket) ends the dashboard and
// brings the login screen back; that is handled here, in `endSession`.
import { fetchCurrentUser, logout, onUnauthorized } from "./hub/api";
import { Dashboard } from "./session/dashboard";
import { Header } from "./header/header";
import { LoginScreen } from "./session/login";
import type { CurrentUser } from "./hub/types";
// Last, so the theme overrides Leaflet's stylesheet (imported by ./map/fleetMap).
// The page's own styles, in cascade order (each panel's beside its code).
import "./styles/base.css";
import "./styles/layout.css";
import "./styles/header.css";
import "./styles/map.css";
import "./styles/fleet.css";
import "./styles/login.css";
import "./styles/audit.css";
import "./styles/replay.css";

const header = new Header();
const appParts = [document.querySelector<HTMLElement>(".app-header")!, document.querySelector<HTMLElement>(".layout")!];
const login = new LoginScreen(startDashboard);
let dashboard: Dashboard | null = null;

function setView(view: "login" | "dashboard"): void {
  document.body.dataset.view = view;
  for (const part of appParts) part.hidden = view !== "dashboard";
}

function showLogin(message = ""): void {
  dashboard?.stop();
  dashboard = null;
  setView("login");
  login.show(message);
}

function startDashboard(user: CurrentUser): void {
  dashboard?.stop();
  setView("dashboard");
  dashboard = new Dashboard(user, header, {
    onUnauthorized: (reason) => endSession(reason),
    logout: () => void signOut(),
  });
  void dashboard.start();
}

/** The hub says the session is over (expired, revoked, or never there). */
function endSession(reason: string): void {
  if (!dashboard) return; // already on the login screen
  showLogin(`Your session has ended (${reason}). Log in again.`);
}

async function signOut(): Promise<void> {
  try {
    await logout();
  } catch (error) {
    // The cookie is HttpOnly: only the hub can clear it, so stay until it has.
    header.showNotice(`Could not log out: ${error instanceof Error ? error.message : String(error)}`);
    return;
  }
  showLogin();
}

onUnauthorized(endSession);

async function boot(): Promise<void> {
  let user: CurrentUser | null = null;
  try {
    user = await fetchCurrentUser();
  } catch (error) {
    showLogin(`Could not reach the hub (${error instanceof Error ? error.message : String(error)}).`);
    return;
  }
  if (user) startDashboard(user);
  else showLogin();
}

void boot();
