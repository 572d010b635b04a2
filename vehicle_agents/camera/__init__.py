"""The camera: photos triggered by the autopilot, posed, geotagged, queued and uploaded.

- `sources`: where the image comes from, behind one interface (the simulator's rendered
  view, a USB/CSI camera through OpenCV, a MAVLink camera's file (`mavlink_camera`), or
  the files a camera writes into a folder (`folder`));
- `trigger`: when: the autopilot's CAMERA_FEEDBACK (ArduPilot) or CAMERA_TRIGGER and
  CAMERA_IMAGE_CAPTURED (PX4, one shutter however many tell of it), and the pose at the
  exposure instant;
- `geotag`: EXIF and XMP in the JPEG, as OpenDroneMap reads them;
- `queue`: the photos waiting on the onboard disk, within a budget;
- `upload`: resumable HTTP uploads to the hub, bounded so telemetry keeps its bandwidth.

Nothing here is imported unless the agent has a camera (``--camera``).
"""
