// The DOM pieces the map's folding panels (survey, formation) build their forms from:
// elements with a class and a `data-field` tests and people read, buttons with a
// `data-action`, labelled number inputs, and a refusal put into words.
import { ApiError, describeErrorBody } from "../hub/api";

export function el<K extends keyof HTMLElementTagNameMap>(tag: K, className: string, field?: string): HTMLElementTagNameMap[K] {
  const made = document.createElement(tag);
  made.className = className;
  if (field) made.dataset.field = field;
  return made;
}

export function button(action: string, text: string, title: string): HTMLButtonElement {
  const made = el("button", "mission-button");
  made.type = "button";
  made.dataset.action = action;
  made.textContent = text;
  made.title = title;
  return made;
}

/** A number input under its label, in a `.map-panel-field` (two to a row in `.map-panel-fields`). */
export function numberField(field: string, label: string, value: string, title: string): [HTMLLabelElement, HTMLInputElement] {
  const wrap = el("label", "map-panel-field");
  const input = el("input", "mission-number", field);
  input.type = "number";
  input.step = "any";
  input.value = value;
  input.title = title;
  wrap.append(label, input);
  return [wrap, input];
}

/** The hub's reason for a refusal (a 422's message, a rails violation), else the error's. */
export function errorText(error: unknown): string {
  if (error instanceof ApiError) return describeErrorBody(error.body, error.status) || error.message;
  return (error as Error).message;
}

/** Shows `text` in a status line, red when `bad`. */
export function say(status: HTMLElement, text: string, bad = false): void {
  status.textContent = text;
  status.classList.toggle("error", bad);
}
