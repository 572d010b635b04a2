"""OpenCV (cv2) for the hub and the simulator, imported without its side effect.

The opencv-python wheels' loader prepends the wheel's own library folder to
``LD_LIBRARY_PATH`` as it imports; its libraries are loaded by then, and every process this
one starts afterwards (a simulator, an agent, a browser) would inherit the change. Import
cv2 from here to leave the environment as it was (tests/unit/project/test_import_side_effects.py).
The agent imports it only for a USB or CSI camera (its optional ``camera`` extra).
"""

from __future__ import annotations

import os

_SAVED = os.environ.get("LD_LIBRARY_PATH")

import cv2  # noqa: E402 - after the environment is saved

if _SAVED is None:
    os.environ.pop("LD_LIBRARY_PATH", None)
else:
    os.environ["LD_LIBRARY_PATH"] = _SAVED

__all__ = ["cv2"]
