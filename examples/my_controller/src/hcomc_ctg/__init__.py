"""hcomc-ctg: a constant-time-gap merge controller for hcomc, registered as ``ctg``."""

from hcomc_ctg.controller import ConstantTimeGap

__all__ = ["ConstantTimeGap"]
