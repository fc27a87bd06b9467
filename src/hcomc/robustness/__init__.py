"""Robustness: merges under a V2X channel with latency and loss, injected faults and a safety
shield, and the campaign that measures them (``hcomc faults``)."""

from hcomc.config.impairment_tables import (
    CHANNELS,
    FAULTS,
    ChannelParams,
    FaultParams,
    ShieldParams,
)

__all__ = ["CHANNELS", "FAULTS", "ChannelParams", "FaultParams", "ShieldParams"]
