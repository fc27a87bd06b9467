"""Optimisers behind one interface: NSGA-II, PSO and SA on arrays, and through pymoo / SciPy."""
