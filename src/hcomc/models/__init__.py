"""Physical sub-models: car following, lane-change paths, transitions, fuel."""
