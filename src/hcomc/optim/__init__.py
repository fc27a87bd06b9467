"""Optimisers behind one interface: NSGA-II and PSO (pymoo), SA (scipy dual_annealing)."""
