// The login screen. The password goes straight from the form to the hub, which
// answers with an HttpOnly session cookie; nothing is kept in JS or storage.
import { ApiError, login } from "../hub/api";
import type { CurrentUser } from "../hub/types";

export class LoginScreen {
  private readonly screen = document.getElementById("login-screen")!;
  private readonly form = document.querySelector<HTMLFormElement>("#login")!;
  private readonly username = this.form.querySelector<HTMLInputElement>('input[name="username"]')!;
  private readonly password = this.form.querySelector<HTMLInputElement>('input[name="password"]')!;
  private readonly submit = this.form.querySelector<HTMLButtonElement>('button[type="submit"]')!;
  private readonly error = this.form.querySelector<HTMLElement>('[data-field="login-error"]')!;
  private busy = false;
  private lockedUntil = 0;
  private unlockTimer: number | undefined;

  constructor(private readonly onLoggedIn: (user: CurrentUser) => void) {
    this.form.addEventListener("submit", (event) => {
      event.preventDefault();
      void this.attempt();
    });
  }

  /** Shows the screen, with `message` (e.g. why the session ended) in the error area. */
  show(message = ""): void {
    this.password.value = "";
    this.setError(message);
    this.screen.hidden = false;
    (this.username.value ? this.password : this.username).focus();
  }

  hide(): void {
    this.screen.hidden = true;
    this.password.value = "";
    this.setError("");
  }

  private async attempt(): Promise<void> {
    if (this.busy || Date.now() < this.lockedUntil) return;
    const username = this.username.value.trim();
    const password = this.password.value;
    if (!username || !password) {
      this.setError("Enter a username and a password.");
      return;
    }
    this.setBusy(true);
    this.setError("");
    try {
      const user = await login(username, password);
      this.hide();
      this.onLoggedIn(user);
    } catch (error) {
      this.password.value = "";
      this.password.focus();
      this.setError(this.describe(error));
    } finally {
      this.setBusy(false);
    }
  }

  private describe(error: unknown): string {
    if (!(error instanceof ApiError)) return String(error);
    if (error.status === 429) {
      const wait = error.retryAfterS;
      if (wait !== null && wait > 0) this.lockFor(wait);
      // The hub's message names the wait; add it from Retry-After if it does not.
      return wait !== null && !/\d\s*s\b/.test(error.message)
        ? `${error.message} (try again in ${Math.ceil(wait)} s)`
        : error.message;
    }
    if (error.status === 0) return "The hub is unreachable; check the connection and try again.";
    return error.message;
  }

  /** Refuses further attempts until the hub's Retry-After has passed. */
  private lockFor(seconds: number): void {
    this.lockedUntil = Date.now() + seconds * 1000;
    window.clearTimeout(this.unlockTimer);
    this.unlockTimer = window.setTimeout(() => {
      this.lockedUntil = 0;
      this.setBusy(this.busy);
    }, seconds * 1000);
    this.setBusy(this.busy);
  }

  private setBusy(busy: boolean): void {
    this.busy = busy;
    this.submit.disabled = busy || Date.now() < this.lockedUntil;
    this.form.setAttribute("aria-busy", String(busy));
    this.submit.textContent = busy ? "Logging in…" : "Log in";
  }

  private setError(message: string): void {
    this.error.textContent = message;
    this.error.hidden = message === "";
  }
}
