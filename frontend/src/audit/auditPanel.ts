// The audit log drawer: who did what, with which token, when, from where and how it
// ended, newest first, a page at a time ("Load older" follows the hub's `next_before_id`).
import { fetchAudit } from "../hub/api";
import { actionButton, element } from "../ui/dom";
import { Pager } from "../ui/pager";
import type { AuditAction, AuditEntry } from "../hub/types";

const PAGE_SIZE = 50;
const COLUMNS = ["time", "actor", "token", "role", "source", "action", "target", "outcome", "detail"] as const;

// Every action the hub records, offered as the action filter's choices (the hub refuses
// any other). A Record, so the compiler says when the generated enum gains one.
const ACTIONS: Record<AuditAction, true> = {
  login: true,
  logout: true,
  "token.create": true,
  "token.revoke": true,
  "user.create": true,
  "user.update": true,
  "agent_token.create": true,
  "agent_token.revoke": true,
  "rails.update": true,
  "rails.clear": true,
  command: true,
  "control.lease": true,
  "formation.start": true,
  "formation.change": true,
  "formation.stop": true,
  denied: true,
};

/** The credential an entry was made with: an API token by name, else its kind. */
export function formatAuditToken(entry: AuditEntry): string {
  if (entry.token) return `${entry.token} (API token ${entry.token_id ?? "?"})`;
  if (entry.token_kind === "api" || entry.token_kind === "agent") {
    return `${entry.token_kind} token ${entry.token_id ?? "?"}`;
  }
  return entry.token_kind ?? "";
}

function pad(value: number): string {
  return String(value).padStart(2, "0");
}

/** Local time as `YYYY-MM-DD HH:MM:SS`: sortable and unambiguous in a log. */
export function formatAuditTime(unixSeconds: number): string {
  const date = new Date(unixSeconds * 1000);
  return (
    `${date.getFullYear()}-${pad(date.getMonth() + 1)}-${pad(date.getDate())} ` +
    `${pad(date.getHours())}:${pad(date.getMinutes())}:${pad(date.getSeconds())}`
  );
}

/** `key=value` pairs on one line; nested values as JSON. */
export function formatAuditDetail(detail: Record<string, unknown> | null): string {
  if (!detail) return "";
  return Object.entries(detail)
    .map(([key, value]) => `${key}=${typeof value === "string" ? value : JSON.stringify(value)}`)
    .join(" ");
}

export class AuditPanel {
  readonly element: HTMLElement;
  private readonly body: HTMLTableSectionElement;
  private readonly actorFilter: HTMLInputElement;
  private readonly actionFilter: HTMLInputElement;
  private readonly pager: Pager<AuditEntry>;
  /** The filters of the list on show, so "Load older" pages the same query. */
  private filters: { actor?: string; action?: string } = {};

  constructor(onClose: () => void) {
    this.actorFilter = element("input", { name: "actor", type: "search", placeholder: "any actor" });
    const actionChoices = element("datalist", { id: "audit-actions" });
    for (const action of Object.keys(ACTIONS)) actionChoices.append(element("option", { value: action }));
    this.actionFilter = element("input", { name: "action", type: "search", placeholder: "any action" });
    this.actionFilter.setAttribute("list", actionChoices.id);
    const refreshButton = actionButton("audit-refresh", "Refresh", () => void this.refresh());
    const filters = element(
      "form",
      { className: "audit-filters" },
      element("label", {}, "Actor ", this.actorFilter),
      element("label", {}, "Action ", this.actionFilter),
      actionChoices,
      refreshButton,
    );
    filters.addEventListener("submit", (event) => {
      event.preventDefault();
      void this.refresh();
    });

    const head = element("tr");
    for (const column of COLUMNS) head.append(element("th", { scope: "col", textContent: column }));
    this.body = element("tbody");
    const table = element("table", { className: "audit-table" }, element("thead", {}, head), this.body);

    const status = element("p", { className: "audit-status" });
    status.dataset.field = "audit-status";
    status.setAttribute("role", "status");
    const moreButton = actionButton("audit-more", "Load older", () => void this.pager.loadOlder());

    this.element = element(
      "aside",
      { id: "audit-panel", className: "audit-panel" },
      element(
        "header",
        { className: "audit-header" },
        element("h2", { textContent: "Audit log" }),
        actionButton("close-audit", "Close", onClose),
      ),
      filters,
      element("div", { className: "audit-scroll" }, table, status, moreButton),
    );
    this.element.setAttribute("aria-label", "Audit log");
    this.element.addEventListener("keydown", (event) => {
      if (event.key === "Escape") onClose();
    });
    this.element.hidden = true;

    this.pager = new Pager<AuditEntry>({
      fetch: async (beforeId) => {
        const page = await fetchAudit({ limit: PAGE_SIZE, beforeId, ...this.filters });
        return { items: page.entries, nextBeforeId: page.next_before_id ?? null };
      },
      clear: () => this.body.replaceChildren(),
      show: (entries) => {
        for (const entry of entries) this.body.append(this.row(entry));
      },
      describe: (more) => {
        const shown = this.body.rows.length;
        if (shown === 0) return "No entries.";
        return more ? "" : `${shown} ${shown === 1 ? "entry" : "entries"}; that is all.`;
      },
      describeError: (message) => `Could not load the audit log: ${message}`,
      status,
      moreButton,
      refreshButton,
      busy: this.element,
    });
  }

  get isOpen(): boolean {
    return !this.element.hidden;
  }

  open(): void {
    this.element.hidden = false;
    void this.refresh();
  }

  close(): void {
    this.element.hidden = true;
  }

  /** Reloads the newest page with the current filters. */
  async refresh(): Promise<void> {
    this.filters = {
      actor: this.actorFilter.value.trim() || undefined,
      action: this.actionFilter.value.trim() || undefined,
    };
    await this.pager.refresh();
  }

  private row(entry: AuditEntry): HTMLTableRowElement {
    const tr = element("tr");
    tr.dataset.auditId = String(entry.id);
    tr.dataset.outcome = entry.outcome;
    const values: Record<(typeof COLUMNS)[number], string> = {
      time: formatAuditTime(entry.time),
      actor: entry.actor,
      token: formatAuditToken(entry),
      role: entry.role,
      source: entry.source,
      action: entry.action,
      target: entry.target,
      outcome: entry.outcome,
      detail: formatAuditDetail(entry.detail),
    };
    for (const column of COLUMNS) {
      const td = element("td", { textContent: values[column], title: values[column] });
      td.dataset.field = column;
      tr.append(td);
    }
    tr.cells[0].title = new Date(entry.time * 1000).toISOString();
    return tr;
  }
}
