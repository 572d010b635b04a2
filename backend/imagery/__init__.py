"""Survey imagery at the hub (issues 21 and 32), one folder: the photos the agents upload
and the live orthomosaic made of them.

- `photos/`: resumable uploads (`ingest.py`, on `uploads.py` for the files and `metadata.py`
  for the first chunk and the survey a photo belongs to), what refuses a photo (`checks.py`),
  uploads in progress (`partials.py`), the OpenDroneMap zip (`export.py`), the rows
  (`repository.py`; the ORM models stay in `storage/models.py`) and the routes (`routes.py`
  on `deps.py`'s `PhotosDep` and the API's `RegistryDep`).
- `mosaic/`: pure: each photo put on the ground (`georef.py`), warped and blended into tiles
  (`engine.py`), kept per survey (`store.py`), its progress (`progress.py`), the queue worked
  off the event loop (`service.py`), the exports (`export.py`); and its routes (`routes.py`
  on `deps.py`'s `MosaicsDep` and the API's `TilesDep`) and its plane in the 3D view
  (`viz_layer.py`).
- `sink.py`: the one place the two meet, each stored photo into its survey's mosaic.

The hub builds the ingest and the mosaics and runs them; the app hands them to the routes
(each folder's `deps.provide`), which never touch the hub object.
"""
