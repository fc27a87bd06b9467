"""Safety: the configuration's Eq. 15 parameters (:mod:`hcomc.safety.critical`) and the
surrogate-measure thresholds; collision detection (paper Eq. 7) and the critical acceleration
(paper Eq. 15) are :mod:`hcomc.equations.collision` and :mod:`hcomc.equations.safety`,
which ``collision``, ``collision_kernels`` and ``critical`` here re-export for one release."""
