// Small DOM helpers shared by the panels.

export function element<K extends keyof HTMLElementTagNameMap>(
  tag: K,
  props: Partial<HTMLElementTagNameMap[K]> = {},
  ...children: (Node | string)[]
): HTMLElementTagNameMap[K] {
  const node = Object.assign(document.createElement(tag), props);
  node.append(...children);
  return node;
}

export function actionButton(action: string, label: string, onClick: () => void): HTMLButtonElement {
  const button = element("button", { type: "button", className: "panel-button", textContent: label });
  button.dataset.action = action;
  button.addEventListener("click", onClick);
  return button;
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

/** Writes only when the text changed (cheap to call every animation frame). */
export function setText(node: HTMLElement, text: string): void {
  if (node.textContent !== text) node.textContent = text;
}
