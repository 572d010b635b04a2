"""The camera `gcs demo` fits every simulated vehicle with, unless told otherwise.

A 1/2-inch 1.2 MP camera (6.4 x 4.8 mm, 1280 x 960 px, 4.8 mm lens): about 4 cm per pixel
and a 53 x 40 m footprint at 40 m. Small enough that the simulators render and the hub
mosaics a four-drone survey's photos on two cores; the hub offers it as a survey preset
named after the vehicles that carry it (backend/survey/fleet_cameras.py), so the demo's
surveys take photos without anyone working out its figures.
"""

from __future__ import annotations

# The agents' --camera-model: sensor width,height (mm),image width,height (px),focal (mm).
DEMO_CAMERA_MODEL = "6.4,4.8,1280,960,4.8"
