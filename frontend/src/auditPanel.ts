// The audit log drawer: who did what, when, from where and how it ended, newest
// first, a page at a time ("Load older" asks for entries before the last id shown).
import { fetchAudit } from "./api";
import { actionButton, element } from "./dom";
import type { AuditEntry } from "./types";

const PAGE_SIZE = 50;
const COLUMNS = ["time", "actor", "role", "source", "action", "target", "outcome", "detail"] as const;

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
  private readonly status: HTMLElement;
  private readonly moreButton: HTMLButtonElement;
  private readonly refreshButton: HTMLButtonElement;
  private readonly actorFilter: HTMLInputElement;
  private readonly actionFilter: HTMLInputElement;
  private lastId: number | null = null;
  /** The filters of the list on show, so "Load older" pages the same query. */
  private filters: { actor?: string; action?: string } = {};
  /** Bumped by every refresh so a slow older page cannot land in a newer list. */
  private generation = 0;
  private loading = false;

  constructor(onClose: () => void) {
    this.actorFilter = element("input", { name: "actor", type: "search", placeholder: "any actor" });
    this.actionFilter = element("input", { name: "action", type: "search", placeholder: "any action" });
    this.refreshButton = actionButton("audit-refresh", "Refresh", () => void this.refresh());
    const filters = element(
      "form",
      { className: "audit-filters" },
      element("label", {}, "Actor ", this.actorFilter),
      element("label", {}, "Action ", this.actionFilter),
      this.refreshButton,
    );
    filters.addEventListener("submit", (event) => {
      event.preventDefault();
      void this.refresh();
    });

    const head = element("tr");
    for (const column of COLUMNS) head.append(element("th", { scope: "col", textContent: column }));
    this.body = element("tbody");
    const table = element("table", { className: "audit-table" }, element("thead", {}, head), this.body);

    this.status = element("p", { className: "audit-status" });
    this.status.dataset.field = "audit-status";
    this.status.setAttribute("role", "status");
    this.moreButton = actionButton("audit-more", "Load older", () => void this.loadOlder());

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
      element("div", { className: "audit-scroll" }, table, this.status, this.moreButton),
    );
    this.element.setAttribute("aria-label", "Audit log");
    this.element.addEventListener("keydown", (event) => {
      if (event.key === "Escape") onClose();
    });
    this.element.hidden = true;
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
    const generation = ++this.generation;
    this.lastId = null;
    this.filters = {
      actor: this.actorFilter.value.trim() || undefined,
      action: this.actionFilter.value.trim() || undefined,
    };
    this.body.replaceChildren();
    this.moreButton.hidden = true;
    await this.load(generation);
  }

  private async loadOlder(): Promise<void> {
    if (this.loading || this.lastId === null) return;
    await this.load(this.generation);
  }

  private async load(generation: number): Promise<void> {
    this.setLoading(true);
    this.setStatus("Loading…");
    try {
      const { entries } = await fetchAudit({
        limit: PAGE_SIZE,
        beforeId: this.lastId ?? undefined,
        ...this.filters,
      });
      if (generation !== this.generation) return;
      for (const entry of entries) this.body.append(this.row(entry));
      if (entries.length > 0) this.lastId = entries[entries.length - 1].id;
      const more = entries.length === PAGE_SIZE;
      this.moreButton.hidden = !more;
      const shown = this.body.rows.length;
      this.setStatus(
        shown === 0 ? "No entries." : more ? "" : `${shown} ${shown === 1 ? "entry" : "entries"}; that is all.`,
      );
    } catch (error) {
      if (generation !== this.generation) return;
      this.setStatus(`Could not load the audit log: ${error instanceof Error ? error.message : String(error)}`);
      // Let the user retry the same page.
      this.moreButton.hidden = this.lastId === null;
    } finally {
      if (generation === this.generation) this.setLoading(false);
    }
  }

  private row(entry: AuditEntry): HTMLTableRowElement {
    const tr = element("tr");
    tr.dataset.auditId = String(entry.id);
    tr.dataset.outcome = entry.outcome;
    const values: Record<(typeof COLUMNS)[number], string> = {
      time: formatAuditTime(entry.time),
      actor: entry.actor,
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

  private setLoading(loading: boolean): void {
    this.loading = loading;
    this.moreButton.disabled = loading;
    this.refreshButton.disabled = loading;
    this.element.setAttribute("aria-busy", String(loading));
  }

  private setStatus(text: string): void {
    this.status.textContent = text;
    this.status.hidden = text === "";
  }
}
