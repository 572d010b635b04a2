"""A survey's geotagged photos as a zip that OpenDroneMap takes as it is.

Inside: ``images/<photo id>.jpg`` (the files as uploaded, EXIF and XMP included),
``image_list.txt`` (one image path per line, relative to the archive's root, as
OpenSfM's image list), and ``geo.txt`` (OpenDroneMap's ``--geo`` file: ``EPSG:4326``,
then per image ``name lon lat alt_msl yaw pitch roll``, the same pose as the EXIF/XMP,
for tools that take positions from a file rather than the images). JPEGs are stored,
not deflated: they do not compress, and storing them costs no CPU. The archive is
written to a temporary file (a survey's photos run to gigabytes) and streamed from it.
"""

from __future__ import annotations

import json
import tempfile
import zipfile
from collections.abc import Sequence
from pathlib import Path

from backend.imagery.photos.repository import PhotoRecord

IMAGES = "images"


def write_zip(records: Sequence[PhotoRecord], folder: Path) -> Path:
    """The archive of ``records`` (stored photos) in a new file under ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    handle = tempfile.NamedTemporaryFile(dir=folder, suffix=".zip", delete=False)  # noqa: SIM115
    handle.close()
    path = Path(handle.name)
    names: list[str] = []
    geo = ["EPSG:4326"]
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as archive:
        for record in records:
            if record.path is None or record.meta_json is None:
                continue
            name = f"{record.photo_id}.jpg"
            archive.write(record.path, f"{IMAGES}/{name}")
            names.append(f"{IMAGES}/{name}")
            pose = json.loads(record.meta_json)["pose"]
            geo.append(
                f"{name} {pose['lon']:.8f} {pose['lat']:.8f} {pose['alt_msl']:.3f} "
                f"{pose['yaw']:.3f} {pose['pitch']:.3f} {pose['roll']:.3f}"
            )
        archive.writestr("image_list.txt", "".join(f"{name}\n" for name in names))
        archive.writestr("geo.txt", "".join(f"{line}\n" for line in geo))
    return path
