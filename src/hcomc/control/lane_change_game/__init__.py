"""The discretionary lane-change game of paper Section III-B: a Stackelberg-Harsanyi game
between the subject vehicle SV and the follower FV in the target lane.

:mod:`~hcomc.control.lane_change_game.decision` plays it (:func:`lane_change_game
<hcomc.control.lane_change_game.decision.lane_change_game>`, called by the engine for a CAV's
discretionary change and by HCOMC for VR's lateral cooperation),
:mod:`~hcomc.control.lane_change_game.params` holds the players' actions, driver types and
parameters, :mod:`~hcomc.control.lane_change_game.costs` the cost terms of a joint action,
:mod:`~hcomc.control.lane_change_game.game_safety` the safety term J_s = a_cr / a_merg it shares
with the merge game (:mod:`hcomc.control.merge_game`) and
:mod:`~hcomc.control.lane_change_game.solvers` the generic two-player solvers. The players'
motion over the horizon is predicted in :mod:`~hcomc.control.lane_change_game.players` (SV's with
the kernel of :mod:`hcomc.control.prediction.game_players`).
"""
