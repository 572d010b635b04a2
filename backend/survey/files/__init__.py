"""Other tools' files: QGroundControl `.plan` and `QGC WPL 110` missions, QGC Survey items,
KML and GeoJSON areas. Pure: text in, our types out, and back."""
