"""Re-exports of :mod:`hcomc.equations`, for one release: the physical sub-models (car following,
lane-change paths, transitions, fuel, the incentive, the ballistic step) moved there, each
module here importing the names of its counterpart. Import from :mod:`hcomc.equations`."""
