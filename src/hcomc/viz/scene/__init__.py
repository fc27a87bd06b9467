"""The top-down road scene of an animation: the frame (:mod:`~hcomc.viz.scene.frame`), the road
and its zones (:mod:`~hcomc.viz.scene.road`) and the virtual vehicles of the plans
(:mod:`~hcomc.viz.scene.ghosts`)."""
