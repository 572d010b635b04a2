"""The area survey (issues 17 and 32), one folder: a newcomer asked "where is the survey?"
has this answer.

- `planning/`: pure: the camera model, the lanes, their bound, the fleet split, the missions.
- `files/`: pure: QGroundControl `.plan` and `QGC WPL 110` missions, QGC Survey items, KML
  and GeoJSON areas.
- `flight/`: pure: a survey in flight as data, its progress and the hand-over's re-split.
- `plan_workers.py`: plans and area files in worker processes, bounded.
- `tracker.py` and `service.py`: following the drones, and what the operators ask;
  `launch.py` sends their commands; `ownership.py`: which hub drives a survey.
- `repository.py`: its rows (the ORM models are the shared schema's, `storage/models.py`).
- `routes.py` on `deps.py`'s `SurveysDep`; `viz_layer.py`: its lanes in the 3D view.

The hub builds the service and runs it; the app hands it to the routes (`deps.provide`).
"""
