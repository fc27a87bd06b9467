"""The equations of the HCOMC paper, in the paper's order, each with one home.

Wang, Wang, Pan, Jiao and Claudel, "HCOMC: A Hierarchical Cooperative On-Ramp Merging Control
Framework in Mixed Traffic Environment on Two-Lane Highways", arXiv:2507.11621. Each module
states its equations with the paper's symbols and wording, the units of every argument and
the choices made where the paper is silent. Every module here is pure: numpy, numba and one
another, no configuration and no engine, so that a kernel's compilation cache depends on
its code alone. Each public function applies a compiled one-vehicle (or one-pair) kernel of
the same module over arrays; the simulation step and the HCOMC prediction call the kernels.

======  ==============================================  ==========================================
Eq.     what it is                                      home
======  ==============================================  ==========================================
1       IDM car following                               :mod:`~hcomc.equations.idm`
        (its IIDM variant)                              :mod:`~hcomc.equations.iidm`
2       HDV inputs: reaction delays, estimation errors  :mod:`~hcomc.equations.perception`
3       CAV car following: ACC with the CAH             :mod:`~hcomc.equations.cav`
1, 3    the acceleration of either vehicle kind         :mod:`~hcomc.equations.car_following`
4-6     quintic lane-change path y(x(t))                :mod:`~hcomc.equations.lane_change`
7       straddle test of two segments (collisions)      :mod:`~hcomc.equations.collision`
8-13    cubic virtual vehicles VV1 and VV2              :mod:`~hcomc.equations.virtual_vehicle`
14      tanh acceleration transition                    :mod:`~hcomc.equations.transition`
15      critical acceleration U_safe                    :mod:`~hcomc.equations.safety`
16      fuel rate and U_fuel                            :mod:`~hcomc.equations.fuel`
17      acceleration incentive U_eff (MOBIL)            :mod:`~hcomc.equations.incentive`
18      the multi-objective problem: Pareto optimality  :mod:`~hcomc.equations.pareto`
19      choice of one plan from the Pareto set          :mod:`~hcomc.equations.selection`
======  ==============================================  ==========================================

Besides the paper's equations: the ballistic integration step of Eqs. (5)-(6)
(:mod:`~hcomc.equations.integrate`), the peaks and shortest duration of a quintic lane change
(:mod:`~hcomc.equations.lane_change_peaks`) and the stopping distance
(:func:`hcomc.equations.safety.stopping_distance`). Eq. (2)'s state per driver (delay buffers,
error processes) stays with the simulation (:mod:`hcomc.sim.perception`), which applies it to
every vehicle of a step. Eq. (18)'s objectives are Eqs. (15)-(17) evaluated on a predicted
merge, which the controller builds
(:meth:`hcomc.control.hierarchical.problem.MergeProblem.evaluate`); its solution concept,
Pareto optimality, is here.
"""
