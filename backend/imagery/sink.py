"""Where the photos meet the mosaic: each stored photo of a survey into that survey's map.

``photos/`` and ``mosaic/`` know nothing of each other (the ingest hands each stored photo
to a ``PhotoSink``); this is the one place that joins them, and the hub wires it.
"""

from __future__ import annotations

from backend.imagery.mosaic.photo import StoredPhoto as MosaicPhoto
from backend.imagery.mosaic.service import MosaicService
from backend.imagery.photos.stored import StoredPhoto


class MosaicSink:
    """The photo ingest's sink: each stored photo of a survey into that survey's mosaic."""

    def __init__(self, mosaic: MosaicService) -> None:
        self._mosaic = mosaic

    async def add_photo(self, photo: StoredPhoto) -> None:
        if photo.survey_id is None:  # no survey, no mosaic to put it in
            return
        await self._mosaic.add_photo(
            MosaicPhoto(
                photo.photo_id,
                photo.vehicle_id,
                photo.survey_id,
                photo.path,
                photo.pose,
                photo.camera,
            )
        )
