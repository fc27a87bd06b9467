"""Paired comparison of merge controllers on common seeds: the effects of one configuration
against another with their confidence intervals and verdicts
(:mod:`~hcomc.experiments.comparison.effects`), merge success
(:mod:`~hcomc.experiments.comparison.success`) and the tables as text
(:mod:`~hcomc.experiments.comparison.view`)."""
