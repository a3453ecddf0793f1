"""The SPL field as perception knows it: its geometry, its map of features, the features seen
in one frame, and localisation from them (seed 004 chapter 2)."""
