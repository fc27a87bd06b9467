"""The prediction every merge controller plans with: the six key vehicles over the horizon.

:func:`~hcomc.control.prediction.population.rollout` simulates a population of candidate plans
with the engine's equations and integration step (its module states the prediction's
assumptions); :mod:`~hcomc.control.prediction.passes` holds the three passes over one
candidate (no-merge counterfactual, virtual vehicles' pre-pass, joint pass),
:mod:`~hcomc.control.prediction.step` one step of car following and integration,
:mod:`~hcomc.control.prediction.accelerations` the key vehicles' accelerations in a step,
:mod:`~hcomc.control.prediction.lane_changes` the quintic lane changes and collisions,
:mod:`~hcomc.control.prediction.scoring` and :mod:`~hcomc.control.prediction.fuel` the scores of
a predicted candidate, :mod:`~hcomc.control.prediction.candidate` a single candidate, and
:mod:`~hcomc.control.prediction.layout` the kernels' array layouts. HCOMC, FIFO and the Game
baseline all predict with it.
"""
