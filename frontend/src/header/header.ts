// The header: connection status, vehicle count, a transient notice line, and who
// is logged in (with the flights, audit-log and logout buttons). On a narrow screen those
// four fold into a menu behind one button (styles/header.css), so the header fits.
import type { ConnectionState } from "../hub/connection";
import { type CurrentUser, can } from "../hub/types";
import { icon } from "../ui/icons";

const NOTICE_MS = 10_000;

export interface UserActions {
  logout(): void;
  /** Only offered to users with the "audit" permission. */
  toggleAudit(): void;
  /** The flight log replay; offered to users with the "read" permission. */
  toggleFlights(): void;
}

export class Header {
  private readonly status = document.getElementById("connection-status")!;
  private readonly count = document.getElementById("vehicle-count")!;
  private readonly notice = document.getElementById("notice")!;
  private readonly userMenu = document.getElementById("user-menu")!;
  private readonly menuToggle = document.getElementById("header-menu-toggle")!;
  private auditButton: HTMLButtonElement | null = null;
  private flightsButton: HTMLButtonElement | null = null;
  private noticeTimer: number | undefined;

  constructor() {
    this.menuToggle.append(icon("menu"));
    this.menuToggle.addEventListener("click", () => this.setMenuOpen(this.menuToggle.getAttribute("aria-expanded") !== "true"));
    // A pick from the menu closes it (the buttons' own handlers still run).
    this.userMenu.addEventListener("click", (event) => {
      if ((event.target as HTMLElement).closest("button")) this.setMenuOpen(false);
    });
  }

  private setMenuOpen(open: boolean): void {
    this.menuToggle.setAttribute("aria-expanded", String(open));
    this.userMenu.parentElement?.classList.toggle("menu-open", open);
  }

  setConnection(state: ConnectionState, retryInMs?: number): void {
    this.status.dataset.state = state;
    document.body.dataset.connection = state;
    this.status.textContent =
      state === "connected"
        ? "Connected"
        : state === "connecting"
          ? "Connecting…"
          : state === "stopped"
            ? "Not connected"
            : retryInMs === undefined
              ? "Reconnecting…"
              : `Reconnecting in ${(retryInMs / 1000).toFixed(1)} s`;
  }

  setCounts(total: number, online: number): void {
    this.count.dataset.count = String(total);
    this.count.dataset.online = String(online);
    const noun = total === 1 ? "vehicle" : "vehicles";
    this.count.textContent = total === online ? `${total} ${noun}` : `${total} ${noun} · ${online} online`;
  }

  /** Shows `text` for a while, or until replaced when `sticky`. */
  showNotice(text: string, sticky = false): void {
    this.notice.textContent = text;
    this.notice.title = text;
    this.notice.hidden = false;
    window.clearTimeout(this.noticeTimer);
    if (!sticky) this.noticeTimer = window.setTimeout(() => (this.notice.hidden = true), NOTICE_MS);
  }

  clearNotice(): void {
    window.clearTimeout(this.noticeTimer);
    this.notice.hidden = true;
    this.notice.textContent = "";
  }

  /** Shows who is logged in and the buttons their permissions allow; null clears it. */
  setUser(user: CurrentUser | null, actions?: UserActions): void {
    this.userMenu.replaceChildren();
    this.auditButton = null;
    this.flightsButton = null;
    this.userMenu.hidden = user === null;
    this.menuToggle.hidden = user === null;
    this.setMenuOpen(false);
    if (!user || !actions) return;

    const name = document.createElement("span");
    name.id = "current-user";
    name.className = "current-user";
    name.dataset.role = user.role;
    name.textContent = `${user.username} · ${user.role}`;
    name.title = `Logged in as ${user.username} (${user.role}); may ${user.permissions.join(", ")}`;
    this.userMenu.append(name);

    if (can(user, "read")) {
      this.flightsButton = headerButton("show-flights", "Flights", () => actions.toggleFlights());
      this.flightsButton.title = "Replay stored flights";
      this.flightsButton.setAttribute("aria-controls", "replay-panel");
      this.flightsButton.setAttribute("aria-expanded", "false");
      this.userMenu.append(this.flightsButton);
    }
    if (can(user, "audit")) {
      this.auditButton = headerButton("show-audit", "Audit log", () => actions.toggleAudit());
      this.auditButton.setAttribute("aria-controls", "audit-panel");
      this.auditButton.setAttribute("aria-expanded", "false");
      this.userMenu.append(this.auditButton);
    }
    this.userMenu.append(headerButton("logout", "Log out", () => actions.logout()));
  }

  setFlightsOpen(open: boolean): void {
    this.flightsButton?.setAttribute("aria-expanded", String(open));
    this.flightsButton?.classList.toggle("active", open);
  }

  setAuditOpen(open: boolean): void {
    this.auditButton?.setAttribute("aria-expanded", String(open));
    this.auditButton?.classList.toggle("active", open);
  }
}

function headerButton(action: string, label: string, onClick: () => void): HTMLButtonElement {
  const button = document.createElement("button");
  button.type = "button";
  button.className = "header-button";
  button.dataset.action = action;
  button.textContent = label;
  button.addEventListener("click", onClick);
  return button;
}
