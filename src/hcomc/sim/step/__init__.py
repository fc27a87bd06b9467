"""The compiled simulation step of one run, over its struct-of-arrays state.

:mod:`~hcomc.sim.step.state` holds the state (:class:`~hcomc.sim.step.state.Core`) and
:mod:`~hcomc.sim.step.build` builds it from a config; :mod:`~hcomc.sim.step.motion` (car
following, collisions, integration, lateral motion), :mod:`~hcomc.sim.step.lane_change` and
:mod:`~hcomc.sim.step.plans` (the merge plans being executed) are the step's kernels, which
:mod:`~hcomc.sim.step.loop` composes into one step and into the loop of many steps between
two controller decisions; :mod:`~hcomc.sim.step.ramp_reach` reads where the ramp vehicles
stand (for the undisturbed twin, :mod:`hcomc.sim.twin`).
"""
