// Pages a newest-first list from the hub, a page at a time: "Refresh" starts again
// from the newest, "Load older" asks for the items before the cursor the last page
// gave. Shared by the flight list and the audit log; each says how to fetch and
// show its items, and words its own status line.

/** One page: its items, and the cursor of the next (older) page, or null at the end. */
export interface Page<T> {
  items: T[];
  nextBeforeId: number | null;
}

export interface PagerView<T> {
  /** Fetches a page: the newest when `beforeId` is undefined. */
  fetch(beforeId: number | undefined): Promise<Page<T>>;
  /** Forgets what is shown (at a refresh, before the first page is asked for). */
  clear(): void;
  /** Shows a page's items below those already shown. */
  show(items: T[]): void;
  /** The status line once a page is shown ("" hides it); `more` when older items exist. */
  describe(more: boolean): string;
  /** The status line when a page could not be loaded. */
  describeError(message: string): string;
  readonly status: HTMLElement;
  readonly moreButton: HTMLButtonElement;
  readonly refreshButton: HTMLButtonElement;
  /** Marked `aria-busy` while a page loads. */
  readonly busy: HTMLElement;
}

export class Pager<T> {
  private nextBeforeId: number | null = null;
  /** Bumped by every refresh so a slow older page cannot land in a newer list. */
  private generation = 0;
  private loadingNow = false;

  constructor(private readonly view: PagerView<T>) {}

  get loading(): boolean {
    return this.loadingNow;
  }

  /** Reloads the newest page. */
  async refresh(): Promise<void> {
    const generation = ++this.generation;
    this.nextBeforeId = null;
    this.view.clear();
    this.view.moreButton.hidden = true;
    await this.load(generation);
  }

  /** Appends the next older page, if there is one and no page is loading. */
  async loadOlder(): Promise<void> {
    if (this.loadingNow || this.nextBeforeId === null) return;
    await this.load(this.generation);
  }

  private async load(generation: number): Promise<void> {
    this.setLoading(true);
    this.setStatus("Loading…");
    try {
      const page = await this.view.fetch(this.nextBeforeId ?? undefined);
      if (generation !== this.generation) return;
      this.view.show(page.items);
      this.nextBeforeId = page.nextBeforeId;
      const more = this.nextBeforeId !== null;
      this.view.moreButton.hidden = !more;
      this.setStatus(this.view.describe(more));
    } catch (error) {
      if (generation !== this.generation) return;
      this.setStatus(this.view.describeError(error instanceof Error ? error.message : String(error)));
      // Let the user retry the same page.
      this.view.moreButton.hidden = this.nextBeforeId === null;
    } finally {
      if (generation === this.generation) this.setLoading(false);
    }
  }

  private setLoading(loading: boolean): void {
    this.loadingNow = loading;
    this.view.moreButton.disabled = loading;
    this.view.refreshButton.disabled = loading;
    this.view.busy.setAttribute("aria-busy", String(loading));
  }

  private setStatus(text: string): void {
    this.view.status.textContent = text;
    this.view.status.hidden = text === "";
  }
}
