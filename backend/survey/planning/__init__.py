"""Planning an area survey: the camera model, the lane planner and the fleet split (issue 17).

Pure logic in a local metric frame: nothing here knows HTTP or the database.
"""
