"""The compiled particle swarm optimiser (the ``pso`` optimiser), which makes the decisions of
pymoo's adaptive PSO on plain arrays: the optimiser (:mod:`~hcomc.optim.pso.optimizer`), its
move and replacement (:mod:`~hcomc.optim.pso.move`) and the fuzzy adaptation of its
coefficients (:mod:`~hcomc.optim.pso.adaptation`)."""
