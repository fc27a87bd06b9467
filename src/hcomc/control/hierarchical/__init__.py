"""HCOMC: hierarchical cooperative planning, the merge problem and the controller."""
