"""Manual control: who may fly a vehicle by hand from the browser, and what input reaches it."""
