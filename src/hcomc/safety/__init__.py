"""Safety geometry: collision detection (Section II-C)."""
