"""The paper's reported numbers (Tables II and III of Wang et al., arXiv:2507.11621).

These are reference data printed next to our results, never used to compute them.
Columns: critical distance [m], average acceleration [m/s^2], stabilisation time [s], LSRV
(the paper's units, "m^2", with an unstated normalisation) and fuel [L].
"""

from __future__ import annotations

PAPER_METRICS = ("critical_distance", "average_acceleration", "stabilisation_time", "lsrv", "fuel")

# Table II: optimisers (HCOMC with NSGA-II, PSO, SA), conditions 1-3
TABLE_II: dict[tuple[str, str], tuple[float, ...]] = {
    ("C1", "PSO"): (108.37, 0.0244, 19.3, 3.9024, 8.0433),
    ("C1", "SA"): (108.45, 0.0243, 19.1, 3.9021, 8.0424),
    ("C1", "NSGA-II"): (114.21, 0.0225, 16.6, 3.8879, 8.0375),
    ("C2", "PSO"): (150.97, 0.0475, 9.3, 3.0009, 8.3909),
    ("C2", "SA"): (150.97, 0.0475, 9.3, 3.0009, 8.3937),
    ("C2", "NSGA-II"): (149.17, 0.0477, 11.8, 2.9996, 8.3982),
    ("C3", "PSO"): (106.18, 0.0517, 19.5, 5.7177, 8.0780),
    ("C3", "SA"): (106.19, 0.0517, 19.7, 5.7177, 8.0779),
    ("C3", "NSGA-II"): (112.01, 0.0494, 17.2, 5.7021, 8.0442),
}

# Table III: controllers (FIFO, Game, HCOMC), conditions 1-5
TABLE_III: dict[tuple[str, str], tuple[float, ...]] = {
    ("C1", "FIFO"): (104.67, 0.0267, 22.5, 3.9122, 8.0660),
    ("C1", "Game"): (108.64, 0.0242, 19.0, 3.9016, 8.0409),
    ("C1", "HCOMC"): (114.21, 0.0225, 16.6, 3.8879, 8.0375),
    ("C2", "FIFO"): (85.47, 0.0442, 26.1, 3.1131, 8.1516),
    ("C2", "Game"): (80.33, 0.0513, 25.4, 3.1444, 8.0598),
    ("C2", "HCOMC"): (149.17, 0.0477, 11.8, 2.9996, 8.3982),
    ("C3", "FIFO"): (102.30, 0.0545, 22.9, 5.7286, 8.1057),
    ("C3", "Game"): (106.53, 0.0515, 19.2, 5.7168, 8.0744),
    ("C3", "HCOMC"): (112.01, 0.0494, 17.2, 5.7021, 8.0442),
    ("C4", "FIFO"): (104.67, 0.0267, 22.5, 3.9125, 8.0510),
    ("C4", "Game"): (108.64, 0.0242, 19.0, 3.9019, 8.0220),
    ("C4", "HCOMC"): (114.21, 0.0225, 16.6, 3.8882, 8.0148),
    ("C5", "FIFO"): (125.62, 0.0427, 20.4, 3.9506, 8.0093),
    ("C5", "Game"): (115.68, 0.0482, 23.1, 3.9727, 7.9763),
    ("C5", "HCOMC"): (129.99, 0.0360, 18.8, 3.9494, 7.8927),
}
