"""Maps: the offline tile sets the hub serves (later the live mosaic's tiles too)."""
