// A small store the views subscribe to by selector: each subscriber names the slice of
// the state it draws (`state => state.selection.id`) and is called only when that slice
// changes, with the new and the old value. Slices are replaced, never mutated, so a
// change is a new object and `Object.is` tells one (a subscriber may pass its own test).

export type Selector<S, T> = (state: S) => T;
export type Listener<T> = (now: T, before: T) => void;
export type Equals<T> = (a: T, b: T) => boolean;

export interface SubscribeOptions<T> {
  /** When two selected values count as the same (default `Object.is`). */
  equals?: Equals<T>;
  /** Call the listener once now with the current slice (as if it changed from it). */
  now?: boolean;
}

interface Subscription<S> {
  /** Looks at the state; calls the listener when its slice changed. */
  check(state: S): void;
}

export class Store<S extends object> {
  private current: S;
  private subscriptions = new Set<Subscription<S>>();

  constructor(initial: S) {
    this.current = initial;
  }

  get state(): Readonly<S> {
    return this.current;
  }

  /** Replaces the named slices and tells the subscribers whose selection changed. */
  set(patch: Partial<S>): void {
    this.current = { ...this.current, ...patch };
    const state = this.current;
    // A listener may set again: that pass tells everyone of the newer state, and this
    // one then finds nothing new for them (each subscriber compares with what it saw).
    for (const subscription of [...this.subscriptions]) {
      if (this.current !== state) return;
      if (this.subscriptions.has(subscription)) subscription.check(state);
    }
  }

  /** Calls `listener` whenever `select(state)` changes; returns the unsubscribe. */
  subscribe<T>(select: Selector<S, T>, listener: Listener<T>, options: SubscribeOptions<T> = {}): () => void {
    const equals = options.equals ?? Object.is;
    let seen = select(this.current);
    const subscription: Subscription<S> = {
      check(state) {
        const next = select(state);
        if (equals(next, seen)) return;
        const before = seen;
        seen = next;
        listener(next, before);
      },
    };
    this.subscriptions.add(subscription);
    if (options.now) listener(seen, seen);
    return () => this.subscriptions.delete(subscription);
  }

  /** Drops every subscriber (the session is over). */
  close(): void {
    this.subscriptions.clear();
  }
}

/** The entries of `now` that are new or replaced since `before` (maps of immutable values). */
export function changedValues<K, V>(now: ReadonlyMap<K, V>, before: ReadonlyMap<K, V>): V[] {
  const changed: V[] = [];
  for (const [key, value] of now) if (before.get(key) !== value) changed.push(value);
  return changed;
}
