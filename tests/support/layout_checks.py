"""Layout faults measured on a live page: elements that run off the viewport, and
visible controls that something else is drawn over. Each returns descriptions, empty
when the page is sound, so a test asserts ``== []`` and a failure names the culprits.

(The layout helper writes the kept version of this module; these are the same names.)"""

from __future__ import annotations

from playwright.sync_api import Page

# An element's description: tag, id, classes, a little of its text, its box.
_DESCRIBE_JS = """
const describe = (element) => {
    const r = element.getBoundingClientRect();
    const id = element.id ? `#${element.id}` : "";
    const cls = typeof element.className === "string" && element.className.trim()
        ? "." + element.className.trim().split(/\\s+/).join(".") : "";
    const text = (element.innerText || element.value || element.getAttribute("aria-label") || "")
        .trim().replace(/\\s+/g, " ").slice(0, 30);
    const [x0, y0, x1, y1] = [r.left, r.top, r.right, r.bottom].map(Math.round);
    return `${element.tagName.toLowerCase()}${id}${cls} "${text}" [${x0},${y0} ${x1},${y1}]`;
};
const shown = (element) => {
    const style = getComputedStyle(element);
    const r = element.getBoundingClientRect();
    // checkVisibility: also false inside a closed <details>, which still has a box.
    return r.width > 0 && r.height > 0 && style.visibility !== "hidden"
        && parseFloat(style.opacity) > 0
        && element.checkVisibility({ checkOpacity: true, checkVisibilityCSS: true });
};
// The part of the box its ancestors' overflow clipping leaves: content scrolled inside a
// panel or laid out past a map's edge is not off the screen, it is clipped.
const clipped = (element) => {
    let { left, top, right, bottom } = element.getBoundingClientRect();
    const fixed = getComputedStyle(element).position === "fixed";
    // Not the page's own clipping: a body that hides its overflow cuts off, not scrolls.
    const roots = [document.body, document.documentElement];
    for (let up = element.parentElement; up && !fixed && !roots.includes(up);) {
        const style = getComputedStyle(up);
        if (style.overflowX !== "visible" || style.overflowY !== "visible") {
            const box = up.getBoundingClientRect();
            if (style.overflowX !== "visible") {
                left = Math.max(left, box.left);
                right = Math.min(right, box.right);
            }
            if (style.overflowY !== "visible") {
                top = Math.max(top, box.top);
                bottom = Math.min(bottom, box.bottom);
            }
        }
        if (getComputedStyle(up).position === "fixed") break;
        up = up.parentElement;
    }
    return { left, top, right, bottom };
};
"""

OVERFLOWING_JS = (
    "() => {"
    + _DESCRIBE_JS
    + """
    const width = document.documentElement.clientWidth, height = window.innerHeight;
    const found = [];
    for (const element of document.body.querySelectorAll("*")) {
        if (!shown(element)) continue;
        const box = clipped(element);
        if (box.right <= box.left || box.bottom <= box.top) continue;  // clipped away
        const out = box.left < -1 || box.right > width + 1
            || box.top < -1 || box.bottom > height + 1;
        // Report the outermost culprit only: its children overflow with it.
        if (out && !found.some((parent) => parent.contains(element))) found.push(element);
    }
    const wide = document.documentElement.scrollWidth;
    const scroll = wide > width + 1 ? [`the page scrolls sideways: ${wide} px in ${width}`] : [];
    return scroll.concat(found.map(describe));
}"""
)

CONTROLS = (
    "button, a[href], input:not([type=hidden]), select, textarea, [role=button], "
    "[role=tab], [role=menuitem]"
)

COVERED_JS = (
    "(selector) => {"
    + _DESCRIBE_JS
    + """
    const width = document.documentElement.clientWidth, height = window.innerHeight;
    const found = [];
    for (const control of document.querySelectorAll(selector)) {
        if (!shown(control) || control.disabled && control.tagName === "INPUT") continue;
        const box = clipped(control);
        const x = (Math.max(box.left, 0) + Math.min(box.right, width)) / 2;
        const y = (Math.max(box.top, 0) + Math.min(box.bottom, height)) / 2;
        // Scrolled out of its panel, or off the screen (the overflow check's business).
        if (box.right - box.left < 2 || box.bottom - box.top < 2) continue;
        if (x < 0 || y < 0 || x > width || y > height) continue;
        const hit = document.elementFromPoint(x, y);
        if (hit === null || control.contains(hit) || hit.contains(control)) continue;
        // A control's own label is part of it (a checkbox in its label).
        const label = hit.closest("label");
        if (label && (label.contains(control) || label.control === control)) continue;
        found.push(`${describe(control)} under ${describe(hit)}`);
    }
    return found;
}"""
)


def overflowing_elements(page: Page) -> list[str]:
    """Visible elements that run past the viewport's edges (not clipped by a scrolling
    or clipping ancestor), and a page that scrolls sideways."""
    found: list[str] = page.evaluate(OVERFLOWING_JS)
    return found


def covered_controls(page: Page) -> list[str]:
    """Visible controls (buttons, links, fields) whose middle another element covers,
    each with what covers it."""
    found: list[str] = page.evaluate(COVERED_JS, CONTROLS)
    return found
