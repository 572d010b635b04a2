"""The live orthomosaic: survey photos onto the ground and into map tiles (issue #21)."""
