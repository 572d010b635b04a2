// The page-side half of tests/support/layout_checks.py: one function, called with what to
// measure ("overflowing" or "covered") and a selector of what may lie over controls (or
// null), returning descriptions of what is wrong.
([kind, allowedOver]) => {
  // An element's tag, id, classes, data-action/field/vehicle-id, start of its text and box.
  const describe = (element) => {
    const box = element.getBoundingClientRect();
    const parts = [element.tagName.toLowerCase()];
    if (element.id) parts.push("#" + element.id);
    const classes = typeof element.className === "string" ? element.className.trim() : "";
    if (classes) parts.push("." + classes.split(/\s+/).join("."));
    for (const name of ["action", "field", "vehicleId"]) {
      const value = element.dataset ? element.dataset[name] : undefined;
      if (value) parts.push(`[${name}=${value}]`);
    }
    const text = (element.textContent || "").trim().slice(0, 30);
    const x = `${Math.round(box.left)}..${Math.round(box.right)}`;
    const y = `${Math.round(box.top)}..${Math.round(box.bottom)}`;
    return `${parts.join("")} "${text}" at x=${x}, y=${y}`;
  };

  // Laid out with a size and drawn: not hidden by a style of its own or an ancestor's, nor
  // inside a closed <details> (whose content keeps a box but is not rendered).
  const shown = (element) => {
    const box = element.getBoundingClientRect();
    if (box.width <= 0 || box.height <= 0) return false;
    return element.checkVisibility({ checkOpacity: true, checkVisibilityCSS: true, contentVisibilityAuto: true });
  };

  // Scrolled out of sight: wholly outside a scrolling ancestor (a list's row scrolled
  // past). Clipping by any other ancestor (the map's edge included) does not count: what
  // a plain clip cuts off is lost to the reader, the fault these checks are for.
  // With `point`, the point (a control's centre, where it is pressed) outside the scrolling
  // ancestor is enough: a control half scrolled past its list's edge is pressed after a
  // scroll, and what lies at its centre meanwhile is whatever is beyond that edge.
  const scrolledAway = (element, point) => {
    const box = element.getBoundingClientRect();
    for (let up = element.parentElement; up && up !== document.body; up = up.parentElement) {
      const style = getComputedStyle(up);
      const scrolls = /auto|scroll/.test(style.overflowX + style.overflowY);
      if (!scrolls) continue;
      const clip = up.getBoundingClientRect();
      const apart = point
        ? point.x < clip.left || point.x > clip.right || point.y < clip.top || point.y > clip.bottom
        : box.right <= clip.left || box.left >= clip.right || box.bottom <= clip.top || box.top >= clip.bottom;
      if (apart) return true;
    }
    return false;
  };

  const overflowing = () => {
    const width = document.documentElement.clientWidth;
    const found = [];
    for (const element of document.body.querySelectorAll("*")) {
      if (!shown(element)) continue;
      // Leaflet's panes and tiles are the map's own canvas, bigger than the map by design
      // and clipped by it: only its controls (what a person reads and presses) count.
      if (element.closest(".leaflet-map-pane")) continue;
      // Inside a drawing, its shapes (a turning horizon) are clipped by the <svg>: the
      // <svg> itself is what is measured.
      if (element instanceof SVGElement && element.ownerSVGElement) continue;
      const box = element.getBoundingClientRect();
      if (box.left >= -0.5 && box.right <= width + 0.5) continue;
      if (!scrolledAway(element)) found.push(describe(element));
    }
    const scrollWidth = document.documentElement.scrollWidth;
    if (scrollWidth > width) found.push(`the page scrolls sideways: ${scrollWidth} px in ${width} px`);
    return found;
  };

  // Controls a person presses or types into, each pressed at its centre.
  const covered = () => {
    const selector = "button, select, input:not([type=hidden]), summary, a[href], [role=button]";
    const found = [];
    for (const control of document.querySelectorAll(selector)) {
      // A control that takes no pointer (map labels while replaying) is not pressed here.
      if (!shown(control) || control.closest("[inert]")) continue;
      if (getComputedStyle(control).pointerEvents === "none") continue;
      const box = control.getBoundingClientRect();
      const x = box.left + box.width / 2;
      const y = box.top + box.height / 2;
      // Off screen or scrolled out of its list is not covered: a scroll brings it back.
      if (x < 0 || y < 0 || x >= innerWidth || y >= innerHeight || scrolledAway(control, { x, y })) continue;
      // On the map's own canvas (a vehicle's label), outside the map's edge: panned away.
      const canvas = control.closest(".leaflet-map-pane") && control.closest(".leaflet-container");
      if (canvas) {
        const edge = canvas.getBoundingClientRect();
        if (x < edge.left || x > edge.right || y < edge.top || y > edge.bottom) continue;
      }
      const hit = document.elementFromPoint(x, y);
      if (hit === null || hit === control || control.contains(hit)) continue;
      // What a menu opened on purpose lies over is not a fault.
      if (allowedOver && hit.closest(allowedOver)) continue;
      // The label round an input is the same control.
      const label = hit.closest("label");
      if (label && label.contains(control)) continue;
      found.push(`${describe(control)} is under ${describe(hit)}`);
    }
    return found;
  };

  return kind === "overflowing" ? overflowing() : covered();
}
