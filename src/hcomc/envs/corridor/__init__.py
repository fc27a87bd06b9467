"""The corridor's learning environments: ``hcomc/CorridorMerge-v0``, in which the agent plans
the merges at every on-ramp of a corridor (:mod:`~hcomc.envs.corridor.env`), its episode on the
engine (:mod:`~hcomc.envs.corridor.episode`) and the PettingZoo form with one agent per
ramp (:mod:`~hcomc.envs.corridor.multi_agent`)."""
