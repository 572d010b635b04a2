"""LIDAR scans on the hub (issue 32: one folder): checked, stored, turned into world
points, mapped, fanned out, routed and drawn in 3D.

- `service.py`: each scan checked, counted, stored, placed and published; the point map.
- `points.py`, `pointmap.py`, `obstacles.py`: pure: world points with a pose per beam,
  the voxel map, the obstacles found in it and their lasting ids.
- `views.py`, `export.py`: what the API and the live feed show of them; PLY files.
- `repository.py`: its rows (the ORM model is the shared schema's, `storage/models.py`).
- `routes.py` on `deps.py`'s typed dependencies, which `app.py` provides.
- `feed.py`: a live feed's scan subscription (realtime uses it as the
  `ScanFeedSubscription` it declares, from the hub).
- `scene_layer.py`: the latest scans and the point map in the 3D view, a `SceneLayer`
  that `app.py` puts on `Hub.scene_layers`.
"""
