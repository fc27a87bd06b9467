"""The Game baseline (paper Table III, "Game"): a 2x2 merge game between the ramp vehicle VR
and the lag vehicle VMC (Liao et al. 2022; Kita 1999).

:mod:`~hcomc.control.merge_game.controller` is the merge controller
(:class:`~hcomc.control.merge_game.controller.GameController`),
:mod:`~hcomc.control.merge_game.payoffs` the players' costs of a predicted joint action and
:mod:`~hcomc.control.merge_game.equilibrium` the game's solution.
"""
