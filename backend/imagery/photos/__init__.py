"""Survey photos at the hub: resumable uploads from the agents, checked, stored, counted,
handed to the live mosaic, and exported for offline photogrammetry."""
