// The one set of DOM helpers every panel builds from: elements with properties and
// children, elements with a class and a `data-field` tests and people read, buttons with
// a `data-action`, labelled number inputs, and status lines.

export function element<K extends keyof HTMLElementTagNameMap>(
  tag: K,
  props: Partial<HTMLElementTagNameMap[K]> = {},
  ...children: (Node | string)[]
): HTMLElementTagNameMap[K] {
  const node = Object.assign(document.createElement(tag), props);
  node.append(...children);
  return node;
}

/** An element with a class and, when given, a `data-field`. */
export function el<K extends keyof HTMLElementTagNameMap>(tag: K, className: string, field?: string): HTMLElementTagNameMap[K] {
  const node = document.createElement(tag);
  node.className = className;
  if (field) node.dataset.field = field;
  return node;
}

/** An element with `data-field`, for the values tests and people read. */
export function field<K extends keyof HTMLElementTagNameMap>(
  tag: K,
  name: string,
  props: Partial<HTMLElementTagNameMap[K]> = {},
): HTMLElementTagNameMap[K] {
  const node = element(tag, props);
  node.dataset.field = name;
  return node;
}

/** A side-panel button with `data-action` that runs `onClick`. */
export function actionButton(action: string, label: string, onClick: () => void): HTMLButtonElement {
  const made = element("button", { type: "button", className: "panel-button", textContent: label });
  made.dataset.action = action;
  made.addEventListener("click", onClick);
  return made;
}

/** A map panel's button (missions, survey, formation) with `data-action` and a tooltip. */
export function button(action: string, text: string, title = ""): HTMLButtonElement {
  const made = element("button", { type: "button", className: "mission-button", textContent: text });
  made.dataset.action = action;
  if (title) made.title = title;
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

/** Writes only when the text changed (cheap to call every animation frame). */
export function setText(node: HTMLElement, text: string): void {
  if (node.textContent !== text) node.textContent = text;
}

/** Shows `text` in a status line, red when `bad`. */
export function say(status: HTMLElement, text: string, bad = false): void {
  status.textContent = text;
  status.classList.toggle("error", bad);
}
